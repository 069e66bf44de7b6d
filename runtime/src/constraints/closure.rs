//! The equations of a loop closure (a cut joint between a predecessor frame P and a successor frame S).
//!
//! Velocity level: the relative motion of S with respect to P, at S's origin, in P's axes:
//! `w = R_Pᵀ(ω_S − ω_P)`, `u = R_Pᵀ(ṗ_S − ṗ_P − ω_P × (p_S − p_P))`; the loop type keeps some components
//! (a revolute cut frees the rotation about its axis, a prismatic cut the translation along it). The
//! position residual is chosen so that its derivative along the motion is exactly these rows wherever
//! the loop is assembled, which is what Newton's method and the finite-difference tests rely on.

use crate::algorithms::Kinematics;
#[allow(unused_imports)]
use crate::alloc_prelude::*;
use crate::model::Model;
use crate::spatial::Transform;
use crate::Real;
use nalgebra::{DMatrix, Matrix3, Vector3};

/// What a cut joint keeps (docs/model-format.md).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum LoopType {
    /// Origins coincide, axes stay aligned: 5 equations.
    Revolute,
    /// Frames aligned, origins differ only along the axis: 5 equations.
    Prismatic,
    /// Origins coincide: 3 equations.
    Spherical,
    /// Frames coincide: 6 equations.
    Fixed,
}

impl LoopType {
    /// Number of scalar equations the loop imposes (before redundant ones are removed).
    pub fn rows(self) -> usize {
        match self {
            LoopType::Revolute | LoopType::Prismatic => 5,
            LoopType::Spherical => 3,
            LoopType::Fixed => 6,
        }
    }
    /// The URDF+ `type` name (`"revolute"`, …).
    pub fn as_str(self) -> &'static str {
        match self {
            LoopType::Revolute => "revolute",
            LoopType::Prismatic => "prismatic",
            LoopType::Spherical => "spherical",
            LoopType::Fixed => "fixed",
        }
    }
}

/// A loop closure between frame P on body `predecessor` and frame S on body `successor` (`None`: the world).
#[derive(Clone, Debug)]
pub struct LoopClosure<T: Real> {
    /// What the cut joint keeps.
    pub kind: LoopType,
    /// The body of frame P, `None` for the world.
    pub predecessor: Option<usize>,
    /// Pose of P in the predecessor body's frame.
    pub predecessor_frame: Transform<T>,
    /// The body of frame S, `None` for the world.
    pub successor: Option<usize>,
    /// Pose of S in the successor body's frame.
    pub successor_frame: Transform<T>,
    /// Unit axis in P.
    pub axis: Vector3<T>,
    /// `e1`, `e2 = axis × e1`: a right-handed basis of the plane normal to the axis.
    pub e1: Vector3<T>,
    /// The second vector of that basis.
    pub e2: Vector3<T>,
}

/// Pose, velocity and velocity-product acceleration (q̈ = 0, no gravity) of a frame, in world axes.
struct FrameState<T: Real> {
    rotation: Matrix3<T>,
    position: Vector3<T>,
    omega: Vector3<T>,
    velocity: Vector3<T>,
    omega_dot: Vector3<T>,
    acceleration: Vector3<T>,
}

impl<T: Real> LoopClosure<T> {
    /// A loop closure of `kind` between the two frames; `axis` (any length, zero for spherical and fixed
    /// loops) is normalized and the basis `e1`, `e2` derived from it.
    pub fn new(
        kind: LoopType,
        predecessor: Option<usize>,
        predecessor_frame: Transform<T>,
        successor: Option<usize>,
        successor_frame: Transform<T>,
        axis: Vector3<T>,
    ) -> Self {
        // (A zero axis is what spherical and fixed loops, which have none, are given.)
        let axis = crate::spatial::unit_vector(&axis).unwrap_or_else(Vector3::x);
        // e1: the unit vector most orthogonal to the axis among x, y, z, projected and normalized.
        let pick = if axis.x.abs() <= axis.y.abs() && axis.x.abs() <= axis.z.abs() {
            Vector3::x()
        } else if axis.y.abs() <= axis.z.abs() {
            Vector3::y()
        } else {
            Vector3::z()
        };
        let e1 = pick - axis * axis.dot(&pick);
        let e1 = e1 / e1.dot(&e1).sqrt();
        let e2 = axis.cross(&e1);
        LoopClosure {
            kind,
            predecessor,
            predecessor_frame,
            successor,
            successor_frame,
            axis,
            e1,
            e2,
        }
    }

    /// The same closure in scalar `U` (through f64).
    pub fn cast<U: Real>(&self) -> LoopClosure<U> {
        let c = |v: &Vector3<T>| v.map(|x| U::from_f64(x.to_f64()));
        LoopClosure {
            kind: self.kind,
            predecessor: self.predecessor,
            predecessor_frame: self.predecessor_frame.cast(),
            successor: self.successor,
            successor_frame: self.successor_frame.cast(),
            axis: c(&self.axis),
            e1: c(&self.e1),
            e2: c(&self.e2),
        }
    }

    fn frame(
        kin: Kinematics<'_, T>,
        body: Option<usize>,
        frame: &Transform<T>,
        with_motion: bool,
    ) -> FrameState<T> {
        let z = Vector3::zeros();
        match body {
            None => FrameState {
                rotation: frame.rotation,
                position: frame.translation,
                omega: z,
                velocity: z,
                omega_dot: z,
                acceleration: z,
            },
            Some(b) => {
                let x = &kin.world_placement[b];
                let r = &x.rotation;
                let c = &frame.translation;
                let (omega, velocity, omega_dot, acceleration) = if with_motion {
                    let v = &kin.velocity[b];
                    let a = &kin.acceleration[b];
                    let vc = v.linear + v.angular.cross(c);
                    (
                        r * v.angular,
                        r * vc,
                        r * a.angular,
                        r * (a.linear + a.angular.cross(c) + v.angular.cross(&vc)),
                    )
                } else {
                    (z, z, z, z)
                };
                FrameState {
                    rotation: r * frame.rotation,
                    position: x.act_point(c),
                    omega,
                    velocity,
                    omega_dot,
                    acceleration,
                }
            }
        }
    }

    /// Position residual (raw rows), from `kin.world_placement`.
    pub fn residual(&self, kin: Kinematics<'_, T>, out: &mut [T]) {
        let mut scale = [T::zero(); 6];
        self.residual_scaled(kin, out, &mut scale[..out.len()]);
    }

    /// [`Self::residual`] and, per row, the magnitude of the numbers it was computed from (what rounding
    /// errors scale with): the larger world coordinate of the two frame origins for a position row (m), 1
    /// for an orientation row. A residual is judged against `max(1, magnitude)` (docs/conventions.md).
    pub fn residual_scaled(&self, kin: Kinematics<'_, T>, out: &mut [T], scale: &mut [T]) {
        let p = Self::frame(kin, self.predecessor, &self.predecessor_frame, false);
        let s = Self::frame(kin, self.successor, &self.successor_frame, false);
        let mut reach = T::zero();
        for x in p.position.iter().chain(s.position.iter()) {
            let a = x.abs();
            reach = a.select_gt(reach, a, reach);
        }
        let one = T::one();
        let position_rows = match self.kind {
            LoopType::Revolute => 2..5,
            LoopType::Prismatic => 3..5,
            LoopType::Spherical => 0..3,
            LoopType::Fixed => 3..6,
        };
        for (k, m) in scale.iter_mut().enumerate() {
            *m = if position_rows.contains(&k) {
                reach
            } else {
                one
            };
        }
        let d = p.rotation.tr_mul(&(s.position - p.position));
        let rel = p.rotation.tr_mul(&s.rotation);
        let half = T::from_f64(0.5);
        // ½ vee(R − Rᵀ): the rotation vector to first order (exact derivative ω_rel at R = I).
        let vee = Vector3::new(
            rel[(2, 1)] - rel[(1, 2)],
            rel[(0, 2)] - rel[(2, 0)],
            rel[(1, 0)] - rel[(0, 1)],
        ) * half;
        match self.kind {
            LoopType::Revolute => {
                let b = rel * self.axis;
                out[0] = self.e1.dot(&b);
                out[1] = self.e2.dot(&b);
                out[2..5].copy_from_slice(d.as_slice());
            }
            LoopType::Prismatic => {
                out[..3].copy_from_slice(vee.as_slice());
                out[3] = self.e1.dot(&d);
                out[4] = self.e2.dot(&d);
            }
            LoopType::Spherical => out[..3].copy_from_slice(d.as_slice()),
            LoopType::Fixed => {
                out[..3].copy_from_slice(vee.as_slice());
                out[3..6].copy_from_slice(d.as_slice());
            }
        }
    }

    /// Keeps the components of `[w; u]` that this loop type constrains, in the order of [`Self::residual`].
    fn select(&self, w: &Vector3<T>, u: &Vector3<T>, out: &mut [T]) {
        match self.kind {
            LoopType::Revolute => {
                out[0] = self.e2.dot(w);
                out[1] = -self.e1.dot(w);
                out[2..5].copy_from_slice(u.as_slice());
            }
            LoopType::Prismatic => {
                out[..3].copy_from_slice(w.as_slice());
                out[3] = self.e1.dot(u);
                out[4] = self.e2.dot(u);
            }
            LoopType::Spherical => out[..3].copy_from_slice(u.as_slice()),
            LoopType::Fixed => {
                out[..3].copy_from_slice(w.as_slice());
                out[3..6].copy_from_slice(u.as_slice());
            }
        }
    }

    /// Rows `row..row + rows()` of the constraint Jacobian `J` (all `nv` columns), from
    /// `kin.world_placement`. Only joints between the loop's common ancestor and its two frames appear.
    pub fn jacobian(
        &self,
        model: &Model<T>,
        kin: Kinematics<'_, T>,
        jac: &mut DMatrix<T>,
        row: usize,
    ) {
        let n = self.kind.rows();
        for r in row..row + n {
            for c in 0..jac.ncols() {
                jac[(r, c)] = T::zero();
            }
        }
        self.for_each_column(model, kin, |v_index, rows| {
            for (r, x) in rows.iter().enumerate() {
                jac[(row + r, v_index)] = *x;
            }
        });
    }

    /// Calls `f(v_index, column)` for each non-zero column of this loop's Jacobian rows.
    pub fn for_each_column(
        &self,
        model: &Model<T>,
        kin: Kinematics<'_, T>,
        mut f: impl FnMut(usize, &[T]),
    ) {
        let p = Self::frame(kin, self.predecessor, &self.predecessor_frame, false);
        let s = Self::frame(kin, self.successor, &self.successor_frame, false);
        let n = self.kind.rows();
        let mut buf = [T::zero(); 6];
        // Joints above S count +1, above P −1; joints above both cancel exactly and are skipped.
        for (body, other, sign) in [
            (self.successor, self.predecessor, T::one()),
            (self.predecessor, self.successor, -T::one()),
        ] {
            let mut cur = body;
            while let Some(b) = cur {
                let above_other = other.is_some_and(|o| b <= o && o < model.subtree_end(b));
                if above_other {
                    break;
                }
                let joint = &model.joints[b];
                let x = &kin.world_placement[b];
                for k in 0..joint.nv() {
                    let m = x.act_motion(&joint.subspace_column(k));
                    let w = p.rotation.tr_mul(&m.angular) * sign;
                    let u = p
                        .rotation
                        .tr_mul(&(m.linear + m.angular.cross(&s.position)))
                        * sign;
                    self.select(&w, &u, &mut buf);
                    f(joint.v_index + k, &buf[..n]);
                }
                cur = model.joints[b].parent;
            }
        }
    }

    /// `J̇ v` (raw rows): the rows' time derivative at q̈ = 0, from `kin.world_placement`, `kin.velocity`
    /// and `kin.acceleration` holding the velocity-product accelerations.
    pub fn bias(&self, kin: Kinematics<'_, T>, out: &mut [T]) {
        let p = Self::frame(kin, self.predecessor, &self.predecessor_frame, true);
        let s = Self::frame(kin, self.successor, &self.successor_frame, true);
        let r = s.position - p.position;
        let rdot = s.velocity - p.velocity;
        let w_world = s.omega - p.omega;
        let u_world = rdot - p.omega.cross(&r);
        // d/dt (R_Pᵀ x) = R_Pᵀ (ẋ − ω_P × x).
        let wdot = p
            .rotation
            .tr_mul(&(s.omega_dot - p.omega_dot - p.omega.cross(&w_world)));
        let udot = p.rotation.tr_mul(
            &(s.acceleration
                - p.acceleration
                - p.omega_dot.cross(&r)
                - p.omega.cross(&rdot)
                - p.omega.cross(&u_world)),
        );
        self.select(&wdot, &udot, out);
    }
}
