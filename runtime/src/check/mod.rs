//! Validation of a model as a pass of its own (in the manner of Pinocchio's `check`): the model stays
//! plain data, and [`crate::ModelBuilder::build`] and [`crate::Model::try_cast`] run these checks on it.
//! Each check reports a [`crate::ModelError`] naming the element at fault.

mod constants;
mod inertia;

use crate::model::{Model, ModelError};
use crate::Real;

/// The checks of a newly built model: every joint's acceleration is determined (its articulated inertia
/// about its axis is positive at the scale of what it moves, in `T`'s precision).
pub(crate) fn check_built<T: Real>(model: &Model<T>) -> Result<(), ModelError> {
    inertia::check_articulated_inertia(model)
}

/// The check before converting `model` to `U`: every constant fits `U`.
pub(crate) fn check_constants_fit<T: Real, U: Real>(model: &Model<T>) -> Result<(), ModelError> {
    constants::check_constants_fit::<T, U>(model)
}

/// The checks of a model converted to `U`: the articulated-inertia check of [`check_built`], again in
/// `U`'s precision.
pub(crate) fn check_converted<U: Real>(model: &Model<U>) -> Result<(), ModelError> {
    inertia::check_articulated_inertia(model)
}
