//! The asymmetric sub-frustum of an image layer ("Layered view-dependent projective textures"
//! §5.1; docs/conventions.md §9.4): the view's `glFrustum` window narrowed to the layer's
//! rectangle, and the texture matrix `T = Bias · Frustum · View` that maps a world point to the
//! layer's texture coordinates `(s/q, t/q)`.
//!
//! Invariants: the full-image rectangle gives back the view's own window; a point's layer texel
//! is its view pixel minus the layer's corner; rectangles are given with rows top-down (the
//! paper's `y` counts from the bottom, `y_i ← h − y_i − h_i`).

use super::image::Rect;
use crate::views::CalibratedView;
use glam::{DMat4, DVec2, DVec3, DVec4};

/// A `glFrustum` window: the near plane's extent in eye space (x right, y up, looking down −z).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Window {
    /// Left.
    pub x_min: f64,
    /// Right.
    pub x_max: f64,
    /// Bottom.
    pub y_min: f64,
    /// Top.
    pub y_max: f64,
    /// Near plane distance.
    pub near: f64,
    /// Far plane distance.
    pub far: f64,
}

impl Window {
    /// The window of a pinhole of focal lengths `(fx, fy)` pixels and principal point
    /// `(cx, cy)` (rows down) over a `w × h` image.
    pub fn of_pinhole(focal: (f64, f64), principal: (f64, f64), (w, h): (u32, u32)) -> Window {
        let near = 0.01;
        let ((fx, fy), (cx, cy)) = (focal, principal);
        Window {
            x_min: -cx * near / fx,
            x_max: (w as f64 - cx) * near / fx,
            y_min: -(h as f64 - cy) * near / fy,
            y_max: cy * near / fy,
            near,
            far: 1e4,
        }
    }

    /// The sub-window of the layer `rect` of a `w × h` image (paper §5.1).
    pub fn layer(&self, (w, h): (u32, u32), rect: Rect) -> Window {
        let (w, h) = (w as f64, h as f64);
        let (xi, wi, hi) = (rect.x as f64, rect.w as f64, rect.h as f64);
        // Rows are top-down here, bottom-up in OpenGL.
        let yi = h - rect.y as f64 - hi;
        let (dx, dy) = (self.x_max - self.x_min, self.y_max - self.y_min);
        Window {
            x_min: self.x_min + xi * dx / w,
            x_max: self.x_min + (xi + wi) * dx / w,
            y_min: self.y_min + yi * dy / h,
            y_max: self.y_min + (yi + hi) * dy / h,
            ..*self
        }
    }

    /// The `glFrustum` matrix.
    pub fn matrix(&self) -> DMat4 {
        let (l, r, b, t, n, f) = (
            self.x_min, self.x_max, self.y_min, self.y_max, self.near, self.far,
        );
        DMat4::from_cols(
            DVec4::new(2.0 * n / (r - l), 0.0, 0.0, 0.0),
            DVec4::new(0.0, 2.0 * n / (t - b), 0.0, 0.0),
            DVec4::new(
                (r + l) / (r - l),
                (t + b) / (t - b),
                -(f + n) / (f - n),
                -1.0,
            ),
            DVec4::new(0.0, 0.0, -2.0 * f * n / (f - n), 0.0),
        )
    }
}

/// Maps world points to one layer's texels.
#[derive(Clone, Debug, PartialEq)]
pub struct LayerProjector {
    /// `Bias · Frustum(layer window) · View`.
    pub texture_matrix: DMat4,
    /// The layer's size in texels.
    pub size: (u32, u32),
}

impl LayerProjector {
    /// The projector of layer `rect` of `view` (an undistorted pinhole).
    pub fn new(view: &CalibratedView, rect: Rect) -> LayerProjector {
        let k = view.intrinsics.undistorted();
        let window = Window::of_pinhole(k.focal(), k.principal_point(), k.size());
        let sub = window.layer(k.size(), rect);
        let bias = DMat4::from_cols(
            DVec4::new(0.5, 0.0, 0.0, 0.0),
            DVec4::new(0.0, 0.5, 0.0, 0.0),
            DVec4::new(0.0, 0.0, 0.5, 0.0),
            DVec4::new(0.5, 0.5, 0.5, 1.0),
        );
        LayerProjector {
            texture_matrix: bias * sub.matrix() * gl_view(view),
            size: (rect.w, rect.h),
        }
    }

    /// The layer texel (continuous, texel centres at `+0.5`, rows down) a world point maps
    /// to, and its eye depth; `None` behind the camera.
    pub fn texel(&self, p: DVec3) -> Option<(DVec2, f64)> {
        let q = self.texture_matrix * p.extend(1.0);
        if q.w <= 1e-12 {
            return None;
        }
        let (s, t) = (q.x / q.w, q.y / q.w);
        Some((
            DVec2::new(s * self.size.0 as f64, (1.0 - t) * self.size.1 as f64),
            q.w,
        ))
    }
}

/// The OpenGL view matrix of a view: its camera frame (x right, y down, z forward) turned to
/// OpenGL's (y up, looking down −z).
fn gl_view(view: &CalibratedView) -> DMat4 {
    let r = glam::DMat3::from_quat(view.pose.rotation);
    let flip = glam::DMat3::from_diagonal(DVec3::new(1.0, -1.0, -1.0));
    let m = flip * r;
    let t = flip * view.pose.translation;
    DMat4::from_cols(
        m.x_axis.extend(0.0),
        m.y_axis.extend(0.0),
        m.z_axis.extend(0.0),
        t.extend(1.0),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::views::{Intrinsics, Pose};

    fn view() -> CalibratedView {
        CalibratedView {
            name: "v".into(),
            image_id: 1,
            camera_id: 1,
            intrinsics: Intrinsics::pinhole(320, 240, 300.0, 310.0, 150.0, 130.0),
            pose: Pose::looking_at(DVec3::new(1.0, 2.0, 5.0), DVec3::ZERO, DVec3::Y)
                .expect("a pose"),
            image: None,
        }
    }

    #[test]
    fn the_full_image_layer_is_the_view_frustum() {
        let w = Window::of_pinhole((300.0, 310.0), (150.0, 130.0), (320, 240));
        let full = w.layer(
            (320, 240),
            Rect {
                x: 0,
                y: 0,
                w: 320,
                h: 240,
            },
        );
        for (a, b) in [
            (w.x_min, full.x_min),
            (w.x_max, full.x_max),
            (w.y_min, full.y_min),
            (w.y_max, full.y_max),
        ] {
            assert!((a - b).abs() < 1e-15);
        }
    }

    #[test]
    fn a_layer_texel_is_the_view_pixel_minus_the_layer_corner() {
        let v = view();
        let rect = Rect {
            x: 37,
            y: 90,
            w: 64,
            h: 40,
        };
        let proj = LayerProjector::new(&v, rect);
        let mut rng = crate::geom::SplitMix64::new(3);
        for _ in 0..100 {
            let p = rng.unit_vector().as_dvec3() * 1.5;
            let (px, z) = v.project(p).expect("in front");
            let (tx, q) = proj.texel(p).expect("in front");
            let want = px - DVec2::new(rect.x as f64, rect.y as f64);
            assert!((tx - want).length() < 1e-8, "{tx} vs {want}");
            assert!((q - z).abs() < 1e-9);
        }
    }
}
