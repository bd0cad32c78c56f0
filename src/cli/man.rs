//! `whitted man [COMMAND]`: the man page of the command or of one subcommand, in roff, generated from
//! the command's clap definitions.

use clap::{Args, CommandFactory};
use clap_mangen::Man;

use super::{Cli, Failure, console};

/// Arguments of `whitted man`.
#[derive(Args)]
pub struct ManArgs {
    /// The subcommand whose page to print (`whitted man render`: whitted-render(1)); the command's
    /// page, which lists the subcommands, if omitted.
    command: Option<String>,
}

/// Prints the page on standard output.
pub fn run(args: &ManArgs) -> Result<(), Failure> {
    // No `help` subcommand: it would be listed as a page that does not exist. Built first, so that
    // each subcommand knows its page's name (whitted-render) and its usage (whitted render).
    let mut cmd = Cli::command().disable_help_subcommand(true);
    cmd.build();
    // Every page's footer names the program and its version (a subcommand's would name only itself).
    let source = format!("{} {}", cmd.get_name(), cmd.get_version().unwrap_or_default());
    let page = match &args.command {
        None => cmd,
        Some(name) => match cmd.find_subcommand(name) {
            Some(sub) => sub.clone(),
            None => {
                let names: Vec<&str> = cmd.get_subcommands().map(|s| s.get_name()).collect();
                return Err(Failure::Usage(whitted::Error::msg(format!(
                    "`{name}` is not a subcommand (the pages are of {})",
                    names.join(", ")
                ))));
            }
        },
    };
    let mut roff = Vec::new();
    Man::new(page)
        .source(source)
        .render(&mut roff)
        .map_err(|e| whitted::Error::msg(format!("cannot render the man page: {e}")))?;
    console::out(String::from_utf8_lossy(&roff))?;
    Ok(())
}
