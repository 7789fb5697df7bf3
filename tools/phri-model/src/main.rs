//! `phri-model`: inspect and benchmark a robot model.
//!
//! ```text
//! phri-model inspect ROBOT.urdf --q v1,v2,… [--qd …] [--qdd …] [--point LINK:x,y,z]
//! phri-model bench ROBOT.urdf [--samples N]
//! phri-model completions bash|zsh|fish|elvish|powershell
//! ```
//! Output is one JSON object on stdout; errors are one line on stderr and exit
//! code 2, among them a result that is not finite (JSON would print `null`) and
//! `--samples` above 100 000.

mod bench;
mod inspect;

use std::process::ExitCode;

use clap::{Parser, Subcommand};

const BIN: &str = "phri-model";

/// The command line.
#[derive(Parser, Debug)]
#[command(
    version = phri_runtime::cli::VERSION,
    about = "Inspects and benchmarks a robot model (URDF): every dynamics term at one state, or the time each algorithm takes, as one JSON object"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Every dynamics term at one state: joints, mimic_joints, M, C, C_qd, Ct_qd, g, tau (RNEA), p, fk and with --point the jacobian
    Inspect(inspect::InspectArgs),
    /// Median nanoseconds per call of each algorithm over random states
    Bench(bench::BenchArgs),
    /// Print a shell completion script to stdout (bash, zsh, fish, elvish or powershell)
    Completions {
        /// Shell to write the script for
        #[arg(value_enum)]
        shell: clap_complete::Shell,
    },
}

/// A comma-separated list of finite numbers (the value of `--q`, `--qd`, `--qdd`).
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Values(pub(crate) Vec<f64>);

/// Parse `v1,v2,…`: every entry a finite number.
pub(crate) fn parse_values(text: &str) -> Result<Values, String> {
    text.split(',')
        .map(|s| {
            let s = s.trim();
            match s.parse::<f64>() {
                Ok(v) if v.is_finite() => Ok(v),
                Ok(_) => Err(format!("'{s}' is not a finite number")),
                Err(_) => Err(format!("'{s}' is not a number")),
            }
        })
        .collect::<Result<Vec<f64>, String>>()
        .map(Values)
}

fn main() -> ExitCode {
    let cli: Cli = phri_runtime::cli::parse(BIN);
    let out = match cli.command {
        Command::Inspect(args) => inspect::run(&args),
        Command::Bench(args) => bench::run(&args),
        Command::Completions { shell } => {
            phri_runtime::cli::completions::<Cli>(BIN, shell);
            return ExitCode::SUCCESS;
        }
    };
    match out {
        Ok(out) => {
            println!("{out}");
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("{BIN}: {e}");
            ExitCode::from(2)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::CommandFactory;

    #[test]
    fn the_command_is_consistent() {
        Cli::command().debug_assert();
    }

    #[test]
    fn values_are_finite_numbers() {
        assert_eq!(
            parse_values("1, -2.5,3e-1"),
            Ok(Values(vec![1.0, -2.5, 0.3]))
        );
        assert!(parse_values("1,inf")
            .unwrap_err()
            .contains("not a finite number"));
        assert!(parse_values("1,,2").unwrap_err().contains("not a number"));
    }
}
