//! The same joint-space dynamics with each body origin moved along its joint axis.
//!
//! `M(q)`, `τ(q, v, q̈)` and `q̈(q, v, τ)` do not depend on where a body's frame sits, only the
//! frame-dependent outputs (poses, Jacobians, wrenches) do. A revolute joint's rotation leaves every point
//! of its axis in place, and a prismatic joint's translation moves every point of its axis along itself,
//! so moving a body's origin by `t·axis` changes no joint transform: it only adds constants to the
//! translations between the body and its parent and children, and shifts the body's inertia. Chosen
//! well, these translations gain zeros, and every frame change of the recursions (a cross product with
//! the translation) loses products; `crba` carries each column of `M` across every joint above it, so a
//! zero near the root pays most. Generated `aba`, `crba`, `minv` and the derivatives are traced on this
//! model (docs/generated-code.md, "Body origins on the joint axes", has the operation counts).

#[allow(unused_imports)]
use crate::alloc_prelude::*;
use crate::model::{JointType, Model};
use crate::spatial::Transform;
use crate::Real;
use nalgebra::{Matrix3, Vector3};

impl<T: Real> Model<T> {
    /// The model with each body origin moved along its joint's axis so that the joint translations have
    /// more zero components where the recursions cross them most (see [`Model::joint_axis_origin_shifts`]);
    /// the joint-space dynamics are the same (to rounding). Body inertias and the poses of the links merged
    /// into each body follow their body's origin.
    ///
    /// Joint placements, inertias and link poses change, so frame-dependent results (body poses, frame
    /// Jacobians, wrenches in body frames) do. A model with constraints (loops refer to points in body
    /// frames) comes back unchanged.
    ///
    /// ```
    /// # use embedyn_runtime as embedyn; // the facade `embedyn` re-exports this crate
    /// use embedyn::nalgebra::{Matrix3, Vector3};
    /// use embedyn::{crba, JointType, Model, SpatialInertia, Transform, Workspace};
    /// // A pendulum whose pivot joint sits 0.3 m along its own axis from the parent's origin.
    /// let mut b = Model::<f64>::builder("pendulum");
    /// let inertia = SpatialInertia::from_com(1.0, Vector3::new(0.0, 0.0, -0.5), Matrix3::identity() * 1e-3);
    /// let placement = Transform::from_xyz_rpy([0.3, 0.0, 0.1], [0.0; 3]);
    /// b.add_body(None, "pivot", JointType::Revolute, Vector3::x(), placement, "bob", inertia).unwrap();
    /// let model = b.build().unwrap();
    /// let moved = model.with_origins_on_joint_axes();
    /// // The origin moved to the parent's x = 0: one zero more in the translation.
    /// assert_eq!(moved.joints[0].placement.translation, Vector3::new(0.0, 0.0, 0.1));
    /// let (mut a, mut b) = (Workspace::new(&model), Workspace::new(&moved));
    /// let q = [0.7];
    /// assert!((crba(&model, &mut a, &q).unwrap()[(0, 0)] - crba(&moved, &mut b, &q).unwrap()[(0, 0)]).abs() < 1e-15);
    /// ```
    pub fn with_origins_on_joint_axes(&self) -> Model<T> {
        let mut moved = self.clone();
        if !self.constraints.is_empty() {
            return moved;
        }
        let shifts = self.joint_axis_origin_shifts();
        let from_f64 = |v: &Vector3<f64>| v.map(T::from_f64);
        for (i, joint) in moved.joints.iter_mut().enumerate() {
            let parent_shift = joint.parent.map_or_else(Vector3::zeros, |p| shifts[p]);
            if parent_shift != Vector3::zeros() || shifts[i] != Vector3::zeros() {
                // In `T`, so that a wider scalar keeps its digits.
                let placement = &mut joint.placement;
                placement.translation = placement.translation
                    + placement.rotation * from_f64(&shifts[i])
                    - from_f64(&parent_shift);
            }
            if shifts[i] == Vector3::zeros() {
                continue;
            }
            // The old body frame seen from the new one: its origin at `-shift`, the same axes.
            let old_in_new = Transform::new(Matrix3::identity(), -from_f64(&shifts[i]));
            let body = &mut moved.bodies[i];
            body.inertia = body.inertia.act(&old_in_new);
            for link in body.link_placements.iter_mut() {
                *link = old_in_new.compose(link);
            }
        }
        moved
    }

    /// What [`Model::joint_axis_origin_shifts`] maximizes (so [`Model::with_origins_on_joint_axes`] never
    /// lowers it): the exact zeros of the joint placements' translations, each joint's counted
    /// [`Model::crossings`] times.
    pub fn weighted_translation_zeros(&self) -> usize {
        self.joints
            .iter()
            .enumerate()
            .map(|(i, j)| {
                let zeros = j.placement.translation.iter().filter(|x| x.to_f64() == 0.0);
                zeros.count() * self.crossings(i)
            })
            .sum()
    }

    /// How often the recursions cross joint `i`'s translation: once in a sweep over the bodies, and once
    /// for each column of `M` carried across it (`crba`), one per velocity coordinate of `i`'s subtree.
    pub fn crossings(&self, i: usize) -> usize {
        1 + self.subtree_v_range(i).len()
    }

    /// Where [`Model::with_origins_on_joint_axes`] puts each body origin: `t·axis` in the body frame, one
    /// vector per body.
    ///
    /// Body `i`'s translation from its moved parent is `w = p − s_parent`; moving its origin by `t·axis`
    /// adds `t·R₀·axis` (`R₀` the joint placement's rotation) to it and takes `t·axis` from each child's.
    /// The moves worth trying are `t = 0` and, for a joint whose axis is an axis of its frame (x, y or
    /// z), each `t` that cancels one component of `w` exactly, no longer than `|w|`. The choice maximizes
    /// the zeros of all translations together, each weighted by how often the recursions cross it
    /// ([`Model::weighted_translation_zeros`]), by a search over the tree that remembers each body's best
    /// for each move of its parent. So a component is passed on toward the leaves, where fewer columns
    /// cross it. Among equals, no move (the file's frame). A floating joint's body stays put: its origin
    /// is where the base velocity is measured, so moving it would change `v`.
    pub fn joint_axis_origin_shifts(&self) -> Vec<Vector3<f64>> {
        let n = self.joints.len();
        let mut children: Vec<Vec<usize>> = vec![Vec::new(); n];
        for (i, joint) in self.joints.iter().enumerate() {
            if let Some(p) = joint.parent {
                children[p].push(i);
            }
        }
        let mut search = ShiftSearch {
            model: self,
            children: &children,
            best: alloc::collections::BTreeMap::new(),
        };
        let mut shifts = vec![Vector3::zeros(); n];
        // Root first: each body's move, given its parent's chosen one, is the remembered best.
        for i in 0..n {
            let parent_shift = self.joints[i]
                .parent
                .map_or_else(Vector3::zeros, |p| shifts[p]);
            let (_, t) = search.best_move(i, &parent_shift);
            shifts[i] = self.joints[i].axis.map(|x| x.to_f64()) * t;
        }
        shifts
    }

    /// The moves of body `i`'s origin along its axis worth trying, given its parent's: `(t, zeros of the
    /// translation from the parent after the move)`, `t = 0` first.
    fn axis_moves(&self, i: usize, parent_shift: &Vector3<f64>) -> Vec<(f64, usize)> {
        let joint = &self.joints[i];
        let w = joint.placement.translation.map(|x| x.to_f64()) - parent_shift;
        let zeros = |v: &Vector3<f64>| v.iter().filter(|x| **x == 0.0).count();
        let mut moves = vec![(0.0, zeros(&w))];
        let axis = joint.axis.map(|x| x.to_f64());
        // Only along an axis of the joint frame: the body's inertia about a tilted axis would come back
        // from the moved origin as a difference of terms of size m·t², which cancel in rounding only
        // (a 10 kg body of 1e-6 kg·m² moved 1 km: 2e-4 relative in `aba`; an attacker's trial). Along
        // a coordinate axis the shift leaves that moment exactly as it was.
        let coordinate_axis = axis.iter().filter(|x| **x != 0.0).count() == 1;
        if coordinate_axis
            && matches!(
                joint.joint_type,
                JointType::Revolute | JointType::Continuous | JointType::Prismatic
            )
        {
            let u = joint.placement.rotation.map(|x| x.to_f64()) * axis;
            for k in 0..3 {
                let t = -w[k] / u[k];
                // No move longer than the translation itself: a nearly perpendicular axis would
                // cancel a component with a long lever arm, and magnify rounding.
                if u[k] != 0.0 && t.is_finite() && t != 0.0 && t.abs() <= w.norm() {
                    moves.push((t, zeros(&(w + u * t))));
                }
            }
        }
        moves
    }
}

/// The search of [`Model::joint_axis_origin_shifts`]: the best zeros of each subtree for a move of its
/// root's parent, remembered by body and move.
struct ShiftSearch<'m, T: Real> {
    model: &'m Model<T>,
    children: &'m [Vec<usize>],
    /// `(body, parent's shift bits)` → `(weighted zeros of the subtree's translations, the body's move)`.
    best: alloc::collections::BTreeMap<(usize, [u64; 3]), (usize, f64)>,
}

impl<T: Real> ShiftSearch<'_, T> {
    /// The most weighted zeros in the translations of body `i`'s joint and of its subtree's, and the move
    /// of `i` that gives them, when `i`'s parent moved by `parent_shift`.
    ///
    /// A depth-first search with its own stack instead of recursion: a chain of ten thousand bodies
    /// overflowed the 2 MB stack of a spawned thread one call per body deep (a regression test holds it).
    fn best_move(&mut self, i: usize, parent_shift: &Vector3<f64>) -> (usize, f64) {
        if let Some(found) = self.best.get(&Self::key(i, parent_shift)) {
            return *found;
        }
        let mut stack = vec![self.visit(i, parent_shift)];
        // What the search of the frame just popped found, for the frame below it.
        let mut returned: Option<usize> = None;
        loop {
            let frame = stack
                .last_mut()
                .expect("the search returns when its stack empties");
            if let Some(zeros) = returned.take() {
                frame.total += zeros;
                frame.child += 1;
            }
            // Advance through the moves and, for each, the children's best, until a child's best is not
            // remembered yet (searched next) or every move is counted.
            let mut descend = None;
            while frame.k < frame.moves.len() {
                let children = &self.children[frame.body];
                if frame.child < children.len() {
                    let c = children[frame.child];
                    match self.best.get(&Self::key(c, &frame.shift)) {
                        Some(found) => {
                            frame.total += found.0;
                            frame.child += 1;
                        }
                        None => {
                            descend = Some((c, frame.shift));
                            break;
                        }
                    }
                    continue;
                }
                // Every child counted for move `k`: `t = 0` first, and a move must do better to be taken.
                let t = frame.moves[frame.k].0;
                if frame.k == 0 || frame.total > frame.found.0 {
                    frame.found = (frame.total, t);
                }
                frame.k += 1;
                if frame.k < frame.moves.len() {
                    self.start_move(frame);
                }
            }
            if let Some((c, shift)) = descend {
                let next = self.visit(c, &shift);
                stack.push(next);
                continue;
            }
            let done = stack.pop().expect("a frame was on the stack");
            self.best
                .insert(Self::key(done.body, &done.parent_shift), done.found);
            match stack.is_empty() {
                true => return done.found,
                false => returned = Some(done.found.0),
            }
        }
    }

    /// The memo's key of body `i` under its parent's move.
    fn key(i: usize, parent_shift: &Vector3<f64>) -> (usize, [u64; 3]) {
        (i, parent_shift.map(f64::to_bits).into())
    }

    /// A new frame of the search for body `i` under its parent's move, at its first move.
    fn visit(&self, i: usize, parent_shift: &Vector3<f64>) -> SearchFrame {
        let mut frame = SearchFrame {
            body: i,
            parent_shift: *parent_shift,
            moves: self.model.axis_moves(i, parent_shift),
            k: 0,
            child: 0,
            shift: Vector3::zeros(),
            total: 0,
            found: (0, 0.0),
        };
        self.start_move(&mut frame);
        frame
    }

    /// Sets `frame` at the start of its move `k`: the body's shift, and its own zeros counted.
    fn start_move(&self, frame: &mut SearchFrame) {
        let (t, zeros) = frame.moves[frame.k];
        frame.shift = self.model.joints[frame.body].axis.map(|x| x.to_f64()) * t;
        frame.total = zeros * self.model.crossings(frame.body);
        frame.child = 0;
    }
}

/// One body's place in [`ShiftSearch::best_move`]'s search: the move it is at, the child it waits for.
struct SearchFrame {
    body: usize,
    parent_shift: Vector3<f64>,
    /// `(t, zeros)` of [`Model::axis_moves`], `t = 0` first.
    moves: Vec<(f64, usize)>,
    /// The move being counted.
    k: usize,
    /// The next child to count for move `k`.
    child: usize,
    /// The body's shift for move `k`.
    shift: Vector3<f64>,
    /// Weighted zeros of move `k` so far.
    total: usize,
    /// The best `(zeros, t)` of the moves counted.
    found: (usize, f64),
}
