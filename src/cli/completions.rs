//! `whitted completions SHELL`: the shell's completion script, generated from the command's clap
//! definitions, so it knows every subcommand and option of the build that prints it.

use clap::{Args, CommandFactory};
use clap_complete::Shell;

use super::{Cli, Failure, console};

/// Arguments of `whitted completions`.
#[derive(Args)]
pub struct CompletionsArgs {
    /// The shell whose script to print.
    shell: Shell,
}

/// Prints the completion script on standard output.
pub fn run(args: &CompletionsArgs) -> Result<(), Failure> {
    let mut cmd = Cli::command();
    let name = cmd.get_name().to_owned();
    let mut script = Vec::new();
    clap_complete::generate(args.shell, &mut cmd, name, &mut script);
    console::out(String::from_utf8_lossy(&script))?;
    Ok(())
}
