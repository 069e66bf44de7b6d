//! The command line's tests, as one test binary (one link, tests in parallel threads; the facade's
//! tests/integration.rs says why). `autotests = false` in cli/Cargo.toml lists it.

mod cli;
mod configuration;
mod contact;
mod derivatives;
mod edges;
mod scale;
mod scene;
mod standalone;
