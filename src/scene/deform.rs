//! Per-frame deformations of an object (paper 1 §6's dynamic scenes): a twist, a bend or a
//! travelling wave, given in the scene file under `[object.deform]` and applied in the object's
//! own frame before it is placed. A deforming object's impostors are rebuilt every frame; a
//! rigidly moving one keeps them.
//!
//! Invariants: the deformation at `t` is a smooth map of object space, the same for any thread
//! count; normals follow it through its Jacobian (inverse transpose, by central differences).

use crate::geom::Mesh;
use glam::{Mat3, Vec3};
use std::f32::consts::TAU;

/// Which deformation.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DeformKind {
    /// A turn about the object's vertical axis, growing from nothing at its base to `amount`
    /// degrees at its top.
    Twist,
    /// A lean about the horizontal `z` axis through its base, growing with the height to
    /// `amount` degrees at its top.
    Bend,
    /// A vertical wave travelling along `x`, of amplitude `amount` × the object's height and
    /// of wavelength `wavelength` × its height.
    Wave,
}

/// A deformation over time, in the object's frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Deformation {
    /// Which.
    pub kind: DeformKind,
    /// Degrees (twist, bend) or a fraction of the height (wave).
    pub amount: f32,
    /// Cycles a second: twist and bend swing as `sin(2π·hz·t)`; the wave travels at `hz`
    /// wavelengths a second.
    pub hz: f32,
    /// Wave only: the wavelength as a fraction of the height.
    pub wavelength: f32,
    /// Centre of the object's base (object space): x and z of its box centre, its lowest y.
    pub base: Vec3,
    /// The object's height in object space (at least a hair above zero).
    pub height: f32,
}

impl Deformation {
    /// A deformation of `mesh` (object space) as the scene file gives it.
    pub fn of(mesh: &Mesh, kind: DeformKind, amount: f32, hz: f32, wavelength: f32) -> Self {
        let b = mesh.bounds();
        let extent = b.extent();
        Self {
            kind,
            amount,
            hz,
            wavelength,
            base: Vec3::new(b.center().x, b.min.y, b.center().z),
            // A flat object (a floor) waves on the scale of its largest extent.
            height: extent
                .y
                .max(1e-3 * extent.max_element())
                .max(f32::MIN_POSITIVE),
        }
    }

    /// Where the deformation at time `t` takes the object-space point `p`.
    pub fn point(&self, p: Vec3, t: f32) -> Vec3 {
        let q = p - self.base;
        let h = q.y / self.height;
        let swing = (TAU * self.hz * t).sin();
        match self.kind {
            DeformKind::Twist => {
                let a = (self.amount * swing * h).to_radians();
                let (s, c) = a.sin_cos();
                self.base + Vec3::new(c * q.x + s * q.z, q.y, -s * q.x + c * q.z)
            }
            DeformKind::Bend => {
                let a = (self.amount * swing * h).to_radians();
                let (s, c) = a.sin_cos();
                self.base + Vec3::new(c * q.x - s * q.y, s * q.x + c * q.y, q.z)
            }
            DeformKind::Wave => {
                let k = TAU / (self.wavelength * self.height);
                let dy = self.amount * self.height * (k * q.x - TAU * self.hz * t).sin();
                p + Vec3::Y * dy
            }
        }
    }

    /// The object-space point `p` with normal `n` carried by the deformation at time `t`: the
    /// point moved, the normal by the Jacobian's inverse transpose.
    pub fn carry(&self, p: Vec3, n: Vec3, t: f32) -> (Vec3, Vec3) {
        let h = 1e-3 * self.height;
        let column =
            |axis: Vec3| (self.point(p + axis * h, t) - self.point(p - axis * h, t)) / (2.0 * h);
        let jacobian = Mat3::from_cols(column(Vec3::X), column(Vec3::Y), column(Vec3::Z));
        (
            self.point(p, t),
            (jacobian.inverse().transpose() * n).normalize_or(n),
        )
    }

    /// `mesh` (object space) deformed at time `t`: positions moved, normals carried by the
    /// Jacobian's inverse transpose ([`Deformation::carry`]).
    pub fn apply(&self, mesh: &Mesh, t: f32) -> Mesh {
        let mut out = mesh.clone();
        for (p, n) in out.positions.iter_mut().zip(out.normals.iter_mut()) {
            (*p, *n) = self.carry(*p, *n, t);
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nothing_moves_at_rest_and_the_base_never_moves() {
        let mesh = crate::geom::cube();
        for kind in [DeformKind::Twist, DeformKind::Bend] {
            let d = Deformation::of(&mesh, kind, 60.0, 0.5, 1.0);
            // sin(0) = 0: at rest.
            for &p in &mesh.positions {
                assert!((d.point(p, 0.0) - p).length() < 1e-6);
            }
            // Points on the base stay put at any time.
            let on_base = d.base + Vec3::new(0.3, 0.0, -0.2);
            assert!((d.point(on_base, 0.37) - on_base).length() < 1e-6);
        }
    }

    #[test]
    fn a_twist_turns_the_top_by_the_amount_and_keeps_normals_unit_and_outward() {
        let mesh = crate::geom::cube();
        let d = Deformation::of(&mesh, DeformKind::Twist, 90.0, 0.25, 1.0);
        // At t = 1 s, sin(2π·0.25) = 1: the top turned 90°.
        let top = d.base + Vec3::new(0.5, d.height, 0.0);
        let turned = d.point(top, 1.0) - d.base;
        assert!(
            (turned - Vec3::new(0.0, d.height, -0.5)).length() < 1e-5,
            "{turned}"
        );
        let twisted = d.apply(&mesh, 1.0);
        let centre = twisted.bounds().center();
        for (p, n) in twisted.positions.iter().zip(&twisted.normals) {
            assert!((n.length() - 1.0).abs() < 1e-4);
            assert!(n.dot(*p - centre) > 0.0, "normal {n} at {p} points inward");
        }
    }
}
