//! `phri-model`: inspect and benchmark a robot model.
//!
//! ```text
//! phri-model inspect ROBOT.urdf --q v1,v2,… [--qd …] [--qdd …] [--point LINK:x,y,z]
//! phri-model bench ROBOT.urdf [--samples N]
//! ```
//! Output is one JSON object on stdout; errors are one line on stderr and exit
//! code 2, among them a result that is not finite (JSON would print `null`) and
//! `--samples` above 100 000.

mod bench;
mod inspect;

use std::process::ExitCode;

const USAGE: &str = "usage:\n  phri-model inspect ROBOT.urdf --q v1,v2,... [--qd ...] [--qdd ...] [--point LINK:x,y,z]\n  phri-model bench ROBOT.urdf [--samples N (at most 100000)]";

/// Parse a comma-separated list of finite numbers for flag `flag`.
pub(crate) fn parse_vector(flag: &str, text: &str) -> Result<Vec<f64>, String> {
    text.split(',')
        .map(|s| {
            let s = s.trim();
            match s.parse::<f64>() {
                Ok(v) if v.is_finite() => Ok(v),
                Ok(_) => Err(format!("{flag}: '{s}' is not a finite number")),
                Err(_) => Err(format!("{flag}: '{s}' is not a number")),
            }
        })
        .collect()
}

/// Flags of the form `--name value` after the positional arguments.
pub(crate) struct Flags {
    pairs: Vec<(String, String)>,
}

impl Flags {
    pub(crate) fn parse(args: &[String], known: &[&str]) -> Result<Flags, String> {
        let mut pairs: Vec<(String, String)> = Vec::new();
        let mut it = args.iter();
        while let Some(a) = it.next() {
            let name = a.as_str();
            if !known.contains(&name) {
                return Err(format!("unknown argument '{name}'\n{USAGE}"));
            }
            let value = it.next().ok_or_else(|| format!("{name} needs a value"))?;
            if pairs.iter().any(|(n, _)| n == name) {
                return Err(format!("{name} given twice"));
            }
            pairs.push((name.to_string(), value.clone()));
        }
        Ok(Flags { pairs })
    }

    pub(crate) fn get(&self, name: &str) -> Option<&str> {
        self.pairs
            .iter()
            .find(|(n, _)| n == name)
            .map(|(_, v)| v.as_str())
    }
}

fn run(args: &[String]) -> Result<String, String> {
    match args.first().map(String::as_str) {
        Some("inspect") => inspect::run(&args[1..]),
        Some("bench") => bench::run(&args[1..]),
        Some("-h") | Some("--help") => Ok(USAGE.to_string()),
        Some(other) => Err(format!("unknown command '{other}'\n{USAGE}")),
        None => Err(USAGE.to_string()),
    }
}

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    match run(&args) {
        Ok(out) => {
            println!("{out}");
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("phri-model: {e}");
            ExitCode::from(2)
        }
    }
}
