//! The reporting seam. Library code never prints: what it has to tell the person running it
//! (a stage starting, something left out and why, a damaged file baked again) and how far a long
//! bake has got go to a [`Reporter`] the caller passes in. The command line's reporter
//! ([`crate::cli::Terminal`]) writes the notes to stderr and draws the bake's progress bar
//! there; [`Silent`] drops everything, for tests, benches and callers that only want results.
//!
//! Results (models, reports, arrays) are never reported: functions return them, and the
//! command line decides what to print.

/// Receives the notes and the bake progress of a run. Shared by the bake's worker threads.
pub trait Reporter: Sync {
    /// One line for the person running the job.
    fn note(&self, line: &str);

    /// A progress display over a bake of `vertices` vertices (every pose still to bake), until
    /// [`BakeProgress::finish`]. The default displays nothing.
    fn bake_progress(&self, vertices: usize) -> Box<dyn BakeProgress + '_> {
        let _ = vertices;
        Box::new(Silent)
    }

    /// A progress display over `steps` steps of a long job made of unequal steps (a sweep of
    /// settings), until [`StepProgress::finish`]. The default displays nothing.
    fn step_progress(&self, steps: usize) -> Box<dyn StepProgress + '_> {
        let _ = steps;
        Box::new(Silent)
    }
}

/// The progress of a job of named steps.
pub trait StepProgress {
    /// Step `what` begins; the previous one is done.
    fn step(&self, what: &str);
    /// Every step is done: the display goes away.
    fn finish(&self);
}

impl StepProgress for Silent {
    fn step(&self, _what: &str) {}
    fn finish(&self) {}
}

/// The progress of one bake, pose by pose and vertex by vertex.
pub trait BakeProgress: Sync {
    /// Pose `index` (from 0) of `count` is being baked.
    fn pose(&self, index: usize, count: usize);
    /// One more vertex is baked (called from the bake's worker threads, in any order).
    fn vertex_done(&self);
    /// Every pose is baked: the display goes away. A bake that fails does not call it.
    fn finish(&self);
}

/// Reports nothing.
#[derive(Clone, Copy, Debug, Default)]
pub struct Silent;

impl Reporter for Silent {
    fn note(&self, _line: &str) {}
}

impl BakeProgress for Silent {
    fn pose(&self, _index: usize, _count: usize) {}
    fn vertex_done(&self) {}
    fn finish(&self) {}
}
