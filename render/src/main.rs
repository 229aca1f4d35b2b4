//! The shared `render` binary (to come, issue 6).
fn main() {}
