//! The command line every phri binary shares: clap for parsing, the flags
//! every service takes ([`ServiceFlags`]), shell completions, and the
//! project's error contract (one line naming the flag, exit 2).
//!
//! A binary declares its own `#[derive(Parser)]` struct (tools), or only its
//! extra flags (services, through [`parse_service`]), and calls [`parse`]:
//! `--help`/`-h` and `--version` print and exit 0, a mistyped flag gets one
//! line with clap's suggestion, and `completions bash|zsh|fish` prints a
//! completion script.

use std::ffi::OsString;
use std::path::PathBuf;

use clap::{Args, CommandFactory, FromArgMatches, Parser, Subcommand};
use clap_complete::Shell;

/// Version line of every binary: the workspace version.
pub const VERSION: &str = env!("CARGO_PKG_VERSION");

/// Flags every service takes.
#[derive(Args, Clone, Debug, Default, PartialEq)]
pub struct ServiceFlags {
    /// Cell configuration (TOML)
    #[arg(long, value_name = "FILE", default_value = "deploy/phri.toml")]
    pub config: PathBuf,
    /// iceoryx2 prefix of the cell [default: phri_]
    #[arg(long, value_name = "PREFIX", env = crate::service::PREFIX_ENV)]
    pub prefix: Option<String>,
    /// SCHED_FIFO priority of the service's real-time thread (0: the normal scheduler)
    #[arg(long, value_name = "N", default_value_t = 0)]
    pub rt_priority: i32,
    /// Override one configuration value, e.g. `--set control.avoidance=false` (repeatable)
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub set: Vec<String>,
    /// Service name as the supervisor knows it (iceoryx2 node name)
    #[arg(long, value_name = "NAME")]
    pub name: Option<String>,
    /// Build everything from the configuration, check it and exit (0: it would run) without opening a channel
    #[arg(long)]
    pub check: bool,
}

impl ServiceFlags {
    /// The cell's prefix: `--prefix`, else `PHRI_PREFIX` when not empty, else `phri_`.
    pub fn prefix(&self) -> String {
        crate::service::prefix_or_default(self.prefix.as_deref().filter(|p| !p.is_empty()))
    }
}

/// The subcommand every binary has: `completions bash|zsh|fish|elvish|powershell`.
#[derive(Subcommand, Clone, Debug, PartialEq)]
pub enum CompletionsCmd {
    /// Print a shell completion script to stdout (bash, zsh, fish, elvish or powershell)
    Completions {
        /// Shell to write the script for
        #[arg(value_enum)]
        shell: Shell,
    },
}

/// A service's whole command line: the shared flags, its own (`E`), and `completions`.
#[derive(Parser, Debug)]
#[command(version = VERSION, args_conflicts_with_subcommands = true)]
struct ServiceCli<E: Args> {
    #[command(flatten)]
    service: ServiceFlags,
    #[command(flatten)]
    extra: E,
    #[command(subcommand)]
    completions: Option<CompletionsCmd>,
}

/// No service-specific flags.
#[derive(Args, Clone, Debug, Default, PartialEq)]
pub struct NoExtra {}

/// Parse a service's command line (the process arguments): `bin` is the
/// binary's name, `about` its one-line description. Exits as [`parse_from`] does.
pub fn parse_service<E: Args + FromArgMatches>(
    bin: &'static str,
    about: &'static str,
) -> (ServiceFlags, E) {
    parse_service_with(bin, about, None)
}

/// [`parse_service`] with a longer description for `--help` (`-h` shows `about`).
pub fn parse_service_with<E: Args + FromArgMatches>(
    bin: &'static str,
    about: &'static str,
    long_about: Option<&'static str>,
) -> (ServiceFlags, E) {
    parse_service_from(bin, about, long_about, std::env::args_os())
}

/// [`parse_service_with`] over given arguments (the first is the program name).
pub fn parse_service_from<E: Args + FromArgMatches>(
    bin: &'static str,
    about: &'static str,
    long_about: Option<&'static str>,
    argv: impl IntoIterator<Item = impl Into<OsString> + Clone>,
) -> (ServiceFlags, E) {
    let cmd = service_command::<E>(bin, about, long_about);
    let cli: ServiceCli<E> = match try_parse_command(cmd.clone(), argv) {
        Ok(c) => c,
        Err(e) => exit_on(bin, e),
    };
    if let Some(CompletionsCmd::Completions { shell }) = cli.completions {
        print_completions(cmd, bin, shell);
        std::process::exit(0);
    }
    (cli.service, cli.extra)
}

/// The clap command of a service with its own flags `E` (for tests and documentation).
pub fn service_command<E: Args + FromArgMatches>(
    bin: &'static str,
    about: &'static str,
    long_about: Option<&'static str>,
) -> clap::Command {
    // `completions` needs none of the service's required flags
    let cmd = ServiceCli::<E>::command()
        .subcommand_negates_reqs(true)
        .name(bin)
        .bin_name(bin)
        .about(about);
    match long_about {
        Some(l) => cmd.long_about(l),
        None => cmd,
    }
}

/// Parse a tool's command line (the process arguments) with its own
/// `#[derive(Parser)]` type; `bin` names it in error lines. `--help`,
/// `--version`: printed, exit 0; anything refused: one line, exit 2.
pub fn parse<T: Parser>(bin: &'static str) -> T {
    parse_from(bin, std::env::args_os())
}

/// [`parse`] over given arguments (the first is the program name).
pub fn parse_from<T: Parser>(
    bin: &'static str,
    argv: impl IntoIterator<Item = impl Into<OsString> + Clone>,
) -> T {
    let cmd = T::command().name(bin).bin_name(bin);
    match try_parse_command(cmd, argv) {
        Ok(t) => t,
        Err(e) => exit_on(bin, e),
    }
}

fn try_parse_command<T: FromArgMatches>(
    cmd: clap::Command,
    argv: impl IntoIterator<Item = impl Into<OsString> + Clone>,
) -> Result<T, clap::Error> {
    let mut matches = cmd.try_get_matches_from(argv)?;
    T::from_arg_matches_mut(&mut matches)
}

/// Write `T`'s completion script for `shell` to stdout (a tool that has its
/// own `completions` subcommand calls this).
pub fn completions<T: CommandFactory>(bin: &'static str, shell: Shell) {
    print_completions(T::command().name(bin).bin_name(bin), bin, shell);
}

fn print_completions(mut cmd: clap::Command, bin: &str, shell: Shell) {
    // into a buffer first: clap_complete panics on a write error, and a
    // closed pipe (`… completions bash | head`) is not one worth a panic
    let mut script = Vec::new();
    clap_complete::generate(shell, &mut cmd, bin, &mut script);
    let _ = std::io::Write::write_all(&mut std::io::stdout().lock(), &script);
}

/// `--help` and `--version` print and exit 0; any other error prints
/// [`one_line`] and exits 2.
fn exit_on(bin: &str, e: clap::Error) -> ! {
    use clap::error::ErrorKind;
    match e.kind() {
        ErrorKind::DisplayHelp
        | ErrorKind::DisplayVersion
        | ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand => e.exit(),
        _ => {
            eprintln!("{bin}: {}", one_line(&e));
            std::process::exit(2);
        }
    }
}

/// clap's error as the project's one line: the message, then any tip
/// (`a similar argument exists: '--config'`), without the usage block.
pub fn one_line(e: &clap::Error) -> String {
    let text = e.render().to_string();
    let mut out = String::new();
    for line in text
        .lines()
        .map(str::trim)
        .take_while(|l| !l.starts_with("Usage:") && !l.starts_with("For more information"))
        .filter(|l| !l.is_empty())
    {
        let line = line.strip_prefix("error: ").unwrap_or(line);
        if !out.is_empty() {
            // a list after "…:" continues the sentence
            out.push_str(if out.ends_with(':') { " " } else { "; " });
        }
        out.push_str(line);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Args, Debug, Default, PartialEq)]
    struct Extra {
        /// worker index
        #[arg(long)]
        worker: Option<u32>,
    }

    #[test]
    fn service_flags_parse_with_equals_and_repeats() {
        let (f, e): (ServiceFlags, Extra) = parse_service_from(
            "phri-test",
            "test",
            None,
            [
                "phri-test",
                "--config=x.toml",
                "--set",
                "a.b=1",
                "--set=c.d=2",
                "--worker",
                "3",
                "--check",
            ],
        );
        assert_eq!(f.config, PathBuf::from("x.toml"));
        assert_eq!(f.set, vec!["a.b=1".to_string(), "c.d=2".to_string()]);
        assert!(f.check);
        assert_eq!(e.worker, Some(3));
        assert_eq!(f.rt_priority, 0);
    }

    #[test]
    fn a_mistyped_flag_is_one_line_with_a_suggestion() {
        let cmd = ServiceCli::<Extra>::command().name("phri-test");
        let err =
            try_parse_command::<ServiceCli<Extra>>(cmd, ["phri-test", "--confg", "x"]).unwrap_err();
        let line = one_line(&err);
        assert!(!line.contains('\n'));
        assert!(line.contains("--confg"), "{line}");
        assert!(line.contains("--config"), "{line}");
        assert!(!line.contains("Usage"), "{line}");
    }

    #[test]
    fn a_bad_value_names_the_flag() {
        let cmd = ServiceCli::<Extra>::command().name("phri-test");
        let err =
            try_parse_command::<ServiceCli<Extra>>(cmd, ["phri-test", "--rt-priority", "high"])
                .unwrap_err();
        let line = one_line(&err);
        assert!(line.contains("--rt-priority"), "{line}");
    }

    #[test]
    fn the_command_is_consistent() {
        ServiceCli::<Extra>::command().debug_assert();
    }
}
