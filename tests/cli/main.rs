//! The command line, run as a user runs it: refusals before any work (`cli_checks`), the reports of
//! `info`, `bench` and `render --stats` parsed as a script reads them (`cli_report`), full and closed
//! standard streams and a FIFO for a scene (`console`), every documented
//! option by a value it must change or keep (`options`), Ctrl-C, SIGTERM and `--resume` (`interrupt`),
//! what the commands do to the files around them (`files`), scenes and images through pipes (`pipes`),
//! split renders merged (`scale_out`), docs/scale-out.md's job array on a Slurm cluster the test
//! starts (`cluster`: early in name order, the order the harness starts tests in, since it mostly waits
//! on its daemons while the others run), and the shell completion scripts and man pages
//! (`completions`).

#[path = "../common/mod.rs"]
mod common;

mod cli_checks;
mod cli_report;
mod cluster;
mod completions;
mod console;
mod files;
mod heatmap;
mod interrupt;
mod options;
mod pipes;
mod scale_out;
