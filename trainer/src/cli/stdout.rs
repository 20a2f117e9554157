//! What commands print on standard output, through one writer that ends quietly when its reader
//! goes away: `println!` panics on a broken pipe (`aprt inspect m.aprt | head -c 0` died with a
//! backtrace and exit code 101).

use std::io::Write;

/// Why a command stopped printing: its standard output was closed (a broken pipe). [`run`]
/// ends on it without a word, as a command whose reader has seen enough.
///
/// [`run`]: crate::cli::run
#[derive(Debug, thiserror::Error)]
#[error("standard output was closed")]
pub struct StdoutClosed;

/// Writes `text` to standard output and flushes it. A closed reader is [`StdoutClosed`]; any
/// other failure (a full disk) is an error saying so.
pub fn print(text: &str) -> anyhow::Result<()> {
    let mut out = std::io::stdout().lock();
    match out.write_all(text.as_bytes()).and_then(|()| out.flush()) {
        Ok(()) => Ok(()),
        Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => Err(StdoutClosed.into()),
        Err(e) => Err(anyhow::Error::new(e).context("cannot write to standard output")),
    }
}

/// `println!` through [`print`]: returns its `Result` rather than panicking.
macro_rules! outln {
    ($($arg:tt)*) => {
        $crate::cli::stdout::print(&format!("{}\n", format_args!($($arg)*)))
    };
}
pub(crate) use outln;
