//! The generated-code equivalence tests that need only the shared helpers, as a test binary of their own
//! beside tests/integration.rs: they are mostly `robot!` expansions (about twenty generated robots), and
//! in a crate of their own rustc compiles them while it compiles the other half of the tests, on the
//! second core (the test suite's longest step was this one crate's build).

mod common;

mod generated;
mod generated_chain;
mod generated_derivatives;
mod generated_lanes;
mod limits;
