//! What the command prints, without a panic whatever becomes of its output. Standard output carries
//! the command's answer: a closed pipe ends the command quietly (as `ls | head` ends `ls`), any other
//! failure (a full disk) is an error. Standard error carries notes and warnings, which must never
//! cost the work: they are written, or dropped where standard error cannot take them.

use std::fmt::Display;
use std::io::{self, Write};

/// Writes `text` to standard output and flushes it. On a closed pipe the reader wants no more: the
/// process ends at once with status 0 (whatever the command wrote to files is complete by then,
/// since its answer is printed last).
pub fn out(text: impl Display) -> whitted::Result<()> {
    out_bytes(text.to_string().as_bytes())
}

/// Writes `bytes` to standard output and flushes them, as [`out`] writes text (an image, `-o -`).
pub fn out_bytes(bytes: &[u8]) -> whitted::Result<()> {
    let mut stdout = io::stdout().lock();
    match stdout.write_all(bytes).and_then(|()| stdout.flush()) {
        Ok(()) => Ok(()),
        Err(e) if e.kind() == io::ErrorKind::BrokenPipe => std::process::exit(0),
        Err(e) => Err(whitted::Error::msg(format!(
            "cannot write to standard output: {e}"
        ))),
    }
}

/// Writes `text` and a newline to standard error, or drops it where standard error cannot take it.
pub fn note(text: impl Display) {
    let _ = writeln!(io::stderr().lock(), "{text}");
}
