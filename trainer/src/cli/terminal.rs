//! The command line's [`Reporter`]: notes are lines on stderr, and a bake shows an `indicatif`
//! progress bar on stderr (drawn only when stderr is a terminal, so logs and tests see the
//! notes alone).

use indicatif::{ProgressBar, ProgressStyle};

use crate::progress::{BakeProgress, Reporter};

/// Reports to the terminal: what `aprt` prints while it works.
#[derive(Clone, Copy, Debug, Default)]
pub struct Terminal;

impl Reporter for Terminal {
    fn note(&self, line: &str) {
        eprintln!("{line}");
    }

    fn bake_progress(&self, vertices: usize) -> Box<dyn BakeProgress + '_> {
        let bar = ProgressBar::new(vertices as u64);
        if let Ok(style) = ProgressStyle::with_template(
            "baking {msg} [{elapsed_precise}] {wide_bar} {pos}/{len} vertices ({eta} left)",
        ) {
            bar.set_style(style);
        }
        Box::new(Bar(bar))
    }
}

/// A bake's progress as a bar over its vertices, with the pose being baked as its message.
struct Bar(ProgressBar);

impl BakeProgress for Bar {
    fn pose(&self, index: usize, count: usize) {
        self.0.set_message(format!("pose {}/{count}", index + 1));
    }

    fn vertex_done(&self) {
        self.0.inc(1);
    }

    fn finish(&self) {
        self.0.finish_and_clear();
    }
}
