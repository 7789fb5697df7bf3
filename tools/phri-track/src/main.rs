//! `phri-track FILE_OR_DIR... --format raw16|png16 --intrinsics FX,FY,CX,CY
//! [--depth-scale-m 0.001] [--width 640 --height 480] [--independent] [--json]`:
//! the model-free person tracker over recorded depth frames (see the library, `phri_track`).

use std::process::ExitCode;

/// `phri-track completions SHELL`, every binary's subcommand.
#[derive(clap::Parser)]
#[command(version)]
struct Completions {
    #[command(subcommand)]
    completions: phri_runtime::cli::CompletionsCmd,
}

fn main() -> ExitCode {
    if std::env::args_os()
        .nth(1)
        .is_some_and(|a| a == "completions")
    {
        let c: Completions = phri_runtime::cli::parse("phri-track");
        let phri_runtime::cli::CompletionsCmd::Completions { shell } = c.completions;
        phri_runtime::cli::completions::<phri_track::Args>("phri-track", shell);
        return ExitCode::SUCCESS;
    }
    let args: phri_track::Args = phri_runtime::cli::parse("phri-track");
    let stdout = std::io::stdout();
    let stderr = std::io::stderr();
    let code = phri_track::run(&args, &mut stdout.lock(), &mut stderr.lock());
    ExitCode::from(code)
}
