//! The codec's tests: the quantiser's bound, round trips, hostile files, the target ratio.

mod hostile;
mod quantiser;
mod sequence;
