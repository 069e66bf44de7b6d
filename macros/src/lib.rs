//! The `robot!` proc-macro: a thin shell over `embedyn-codegen`.
//!
//! Code generation arrives with the code-generation issue; until then this crate exports nothing, so that
//! the workspace layout (runtime ← codegen ← macros ← facade) is fixed from the start.
