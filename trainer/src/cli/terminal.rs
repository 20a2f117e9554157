//! The command line's [`Reporter`]: notes are lines on stderr, and a bake shows an `indicatif`
//! progress bar on stderr (drawn only when stderr is a terminal, so logs and tests see the
//! notes alone).

use indicatif::{ProgressBar, ProgressStyle};

use crate::progress::{BakeProgress, Reporter, StepProgress};

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

    fn step_progress(&self, steps: usize) -> Box<dyn StepProgress + '_> {
        let bar = ProgressBar::new(steps as u64);
        if let Ok(style) = ProgressStyle::with_template(
            "{msg} [{elapsed_precise}] {wide_bar} {pos}/{len} steps ({eta} left)",
        ) {
            bar.set_style(style);
        }
        Box::new(Steps(bar))
    }
}

/// A job's progress as a bar over its steps, with the current step as its message.
struct Steps(ProgressBar);

impl StepProgress for Steps {
    fn step(&self, what: &str) {
        if !self.0.message().is_empty() {
            self.0.inc(1);
        }
        self.0.set_message(what.to_owned());
    }

    fn finish(&self) {
        self.0.finish_and_clear();
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
