//! The `aprt` command line.

fn main() {}
