//! Whether every constant of a model fits another scalar type, checked before [`Model::try_cast`]
//! converts it: a ratio of 1e300 does not exist in f32, and converting it would silently give another
//! model (or, in generated code, a literal that does not compile).
//!
//! A constant does not fit when it becomes infinite, or when it is *significant* and becomes zero or
//! subnormal (keeping fewer bits than the type's precision). Significant means at least ε times the
//! largest constant of the same kind in the model (lengths, masses, first moments, rotational
//! inertias, gravity, one constraint's coefficients): a 1e-40 m offset in a metre-sized robot is below
//! what the type resolves anyway and may flush to zero; a 1e-40 coefficient that is the largest of
//! its constraint, or a model whose masses all underflow, would change the model. Whether the
//! converted inertias still determine every joint's acceleration is checked separately, by the
//! articulated-inertia check run in the new type.

#[allow(unused_imports)]
use crate::alloc_prelude::*;
use crate::constraints::ConstraintKind;
use crate::model::{Model, ModelElement, ModelError};
use crate::spatial::Transform;
use crate::Real;

/// The kinds of constants whose magnitudes are comparable (same unit and role).
#[derive(Clone, Copy, PartialEq, Eq)]
enum Kind {
    Length,
    Mass,
    FirstMoment,
    RotationalInertia,
    /// Rotation matrices and unit axes: entries at most 1.
    Direction,
    Gravity,
    /// The coefficients of one linear constraint (its own scale).
    Coefficients,
    /// A constraint's offset: only its finiteness matters (a coordinate offset below 1e-38 moves
    /// nothing any scalar resolves).
    Offset,
}

const KINDS: [Kind; 8] = [
    Kind::Length,
    Kind::Mass,
    Kind::FirstMoment,
    Kind::RotationalInertia,
    Kind::Direction,
    Kind::Gravity,
    Kind::Coefficients,
    Kind::Offset,
];

/// One group of constants: what they belong to, what they are, their kind.
struct Constants {
    element: ModelElement,
    what: &'static str,
    kind: Kind,
    values: Vec<f64>,
}

fn transform<T: Real>(
    out: &mut Vec<Constants>,
    element: &ModelElement,
    what: [&'static str; 2],
    x: &Transform<T>,
) {
    out.push(Constants {
        element: element.clone(),
        what: what[0],
        kind: Kind::Direction,
        values: x.rotation.iter().map(|v| v.to_f64()).collect(),
    });
    out.push(Constants {
        element: element.clone(),
        what: what[1],
        kind: Kind::Length,
        values: x.translation.iter().map(|v| v.to_f64()).collect(),
    });
}

/// Every constant of the model, grouped by what it belongs to.
fn constants<T: Real>(model: &Model<T>) -> Vec<Constants> {
    let mut out = Vec::new();
    let f = |v: &T| v.to_f64();
    out.push(Constants {
        element: ModelElement::Gravity,
        what: "value",
        kind: Kind::Gravity,
        values: model.gravity.iter().map(f).collect(),
    });
    for j in &model.joints {
        let element = ModelElement::Joint(j.name.clone());
        transform(
            &mut out,
            &element,
            ["placement rotation", "placement translation"],
            &j.placement,
        );
        if j.has_armature() {
            // A reflected rotor's ratio² · inertia (a ratio of 1e25 is 1e50 of it): named as armature,
            // not as whatever inertia the overflow would poison later.
            out.push(Constants {
                element: element.clone(),
                what: "armature",
                kind: Kind::RotationalInertia,
                values: vec![j.armature.to_f64()],
            });
        }
        out.push(Constants {
            element,
            what: "axis",
            kind: Kind::Direction,
            values: j.axis.iter().map(f).collect(),
        });
    }
    for b in &model.bodies {
        let element = ModelElement::Body(b.name.clone());
        let i = &b.inertia;
        for (what, kind, values) in [
            ("mass", Kind::Mass, vec![i.mass.to_f64()]),
            (
                "first moment of mass",
                Kind::FirstMoment,
                i.first_moment.iter().map(f).collect(),
            ),
            (
                "rotational inertia",
                Kind::RotationalInertia,
                i.rotational.iter().map(f).collect(),
            ),
        ] {
            out.push(Constants {
                element: element.clone(),
                what,
                kind,
                values,
            });
        }
        for (link, x) in b.links.iter().zip(&b.link_placements) {
            transform(
                &mut out,
                &ModelElement::Body(link.clone()),
                ["frame rotation", "frame translation"],
                x,
            );
        }
    }
    for c in &model.constraints {
        let element = ModelElement::Constraint(c.name.clone());
        match &c.kind {
            ConstraintKind::Linear { terms, offset } => {
                out.push(Constants {
                    element: element.clone(),
                    what: "coefficient",
                    kind: Kind::Coefficients,
                    values: terms.iter().map(|(_, k)| k.to_f64()).collect(),
                });
                // The model's row is `Σ k q + offset = 0`, a mimic's `q = m q_d + o` written as
                // `q − m q_d − o = 0`: the offset the file wrote is `−offset` (an attacker's trial: an
                // offset of 1e39 was reported as −1e39). A coupling's is 0.
                out.push(Constants {
                    element,
                    what: "offset",
                    kind: Kind::Offset,
                    values: vec![-offset.to_f64()],
                });
            }
            ConstraintKind::Loop(l) => {
                transform(
                    &mut out,
                    &element,
                    [
                        "predecessor frame rotation",
                        "predecessor frame translation",
                    ],
                    &l.predecessor_frame,
                );
                transform(
                    &mut out,
                    &element,
                    ["successor frame rotation", "successor frame translation"],
                    &l.successor_frame,
                );
                out.push(Constants {
                    element,
                    what: "axis",
                    kind: Kind::Direction,
                    values: [l.axis, l.e1, l.e2]
                        .iter()
                        .flat_map(|v| v.iter().map(f))
                        .collect(),
                });
            }
        }
    }
    out
}

/// Fails naming the first constant of `model` that does not fit `U` (see the module documentation).
pub(crate) fn check_constants_fit<T: Real, U: Real>(model: &Model<T>) -> Result<(), ModelError> {
    let all = constants(model);
    let largest = |v: &[f64]| v.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    let scale_of = |kind: Kind| -> f64 {
        match kind {
            Kind::Direction => 1.0,
            _ => all
                .iter()
                .filter(|c| c.kind == kind)
                .fold(0.0f64, |m, c| m.max(largest(&c.values))),
        }
    };
    let scales: Vec<(Kind, f64)> = KINDS.iter().map(|&k| (k, scale_of(k))).collect();
    let eps = U::epsilon().to_f64();
    for c in &all {
        let scale = match c.kind {
            Kind::Coefficients => largest(&c.values),
            kind => scales.iter().find(|(k, _)| *k == kind).map_or(0.0, |s| s.1),
        };
        for &x in &c.values {
            let converted = U::from_f64(x).to_f64();
            let too_large = !converted.is_finite();
            // Significant, and rounded by more than the type's precision: it fell below the normal range.
            let too_small = c.kind != Kind::Offset
                && x.abs() >= eps * scale
                && (converted - x).abs() > eps * x.abs();
            if too_large || too_small {
                return Err(ModelError::ConstantDoesNotFit {
                    element: c.element.clone(),
                    what: c.what,
                    value: x,
                    scalar: U::NAME,
                    too_large,
                });
            }
        }
    }
    Ok(())
}
