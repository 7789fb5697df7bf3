//! phri-lint: prints every function of the workspace longer than a limit
//! (default 120 lines) outside test code, longest first, as
//! `path:line  lines  name`. The check itself is `cargo test -p phri-lint`.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use clap::{Parser, Subcommand};

const BIN: &str = "phri-lint";

/// The command line.
#[derive(Parser, Debug)]
#[command(
    version = phri_runtime::cli::VERSION,
    about = "Lists every function of the workspace longer than a limit outside test code, longest first",
    args_conflicts_with_subcommands = true
)]
struct Cli {
    /// Longest function allowed [lines]
    #[arg(value_name = "LIMIT", default_value_t = phri_lint::MAX_FUNCTION_LINES)]
    limit: usize,
    /// Workspace to read [default: the one this binary was built from]
    #[arg(value_name = "ROOT")]
    root: Option<PathBuf>,
    #[command(subcommand)]
    command: Option<Command>,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Print a shell completion script to stdout (bash, zsh, fish, elvish or powershell)
    Completions {
        /// Shell to write the script for
        #[arg(value_enum)]
        shell: clap_complete::Shell,
    },
}

fn main() -> ExitCode {
    let cli: Cli = phri_runtime::cli::parse(BIN);
    if let Some(Command::Completions { shell }) = cli.command {
        phri_runtime::cli::completions::<Cli>(BIN, shell);
        return ExitCode::SUCCESS;
    }
    let root = cli
        .root
        .unwrap_or_else(|| Path::new(env!("CARGO_MANIFEST_DIR")).join("../.."));
    let mut long = match phri_lint::long_functions(&root, cli.limit) {
        Ok(long) => long,
        Err(e) => {
            eprintln!("{BIN}: {e}");
            return ExitCode::FAILURE;
        }
    };
    long.sort_by_key(|f| std::cmp::Reverse(f.lines));
    for f in &long {
        println!("{}:{}\t{}\t{}", f.path, f.line, f.lines, f.name);
    }
    println!("{} functions over {} lines", long.len(), cli.limit);
    ExitCode::SUCCESS
}
