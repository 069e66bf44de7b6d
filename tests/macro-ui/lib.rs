//! Nothing: this crate only holds the `robot!` compile-error tests (`ui.rs`).
