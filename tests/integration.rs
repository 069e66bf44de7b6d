//! The facade's integration tests, as one test binary.
//!
//! Each file beside this one is a module of it rather than a binary of its own: every test binary links
//! the whole of embedyn and instantiates its generic solver for its scalars again, so fifteen binaries
//! cost fifteen links and fifteen copies of the same optimized code, and `cargo test` runs binaries one
//! after another where the tests of one binary run in parallel. Four stay apart, for reasons of their own:
//! `no_allocation` (its counting global allocator must see no other test's allocations), `hostile_names`
//! (`#![deny(warnings)]` over the whole crate the macro expands into), `ui` (trybuild compiles crates
//! of its own) and `generated_code` (tests/generated_code.rs: the modules that are mostly `robot!`
//! expansions, so that rustc compiles the two halves of the generated code at once on two cores).
//! `autotests = false` in Cargo.toml lists the binaries.

mod common;

mod armature;
mod bad_input;
mod configuration;
mod constraint_embedding;
mod contact;
mod contact_invariants;
mod contact_sweep;
mod derivatives;
mod dynamics_oracles;
mod energy;
mod extremes;
mod fuzz_corpus;
mod fuzz_findings;
mod generated_contact;
mod gravity_nle;
mod joint_axis_origins;
mod loop_simulation;
mod model_scale;
mod pinocchio_reference;
mod precision;
mod random_loops;
mod random_trees;
mod scene_options;
