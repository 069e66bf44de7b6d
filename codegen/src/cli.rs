//! The `embedyn` command line.
