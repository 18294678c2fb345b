//! COLMAP's camera models: intrinsics, lens distortion applied exactly when projecting, and its
//! inverse (undistortion) by Newton's method. A calibrated view's camera
//! ([`crate::views::CalibratedView`]), and the lens a render camera's pixels may look through
//! ([`crate::scene::View::lens`]: each pixel sees along its undistorted pinhole's ray through
//! [`Intrinsics::undistorted_pixel_of`]).
//!
//! Pixel coordinates follow COLMAP and trompe alike: `(0, 0)` is the top-left corner of the
//! top-left pixel, whose centre is `(0.5, 0.5)`. A camera looks down its `+z`, `x` right, `y`
//! down; `(u, v) = (x/z, y/z)` are normalised image coordinates.

use glam::DVec2;

/// The camera models trompe reads, with COLMAP's ids and parameter lists.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CameraModel {
    /// `f, cx, cy`.
    SimplePinhole,
    /// `fx, fy, cx, cy`.
    Pinhole,
    /// `f, cx, cy, k`.
    SimpleRadial,
    /// `f, cx, cy, k1, k2`.
    Radial,
    /// `fx, fy, cx, cy, k1, k2, p1, p2`.
    OpenCv,
    /// `fx, fy, cx, cy, k1, k2, p1, p2, k3, k4, k5, k6`.
    FullOpenCv,
}

impl CameraModel {
    /// Every model, in COLMAP id order.
    pub const ALL: [CameraModel; 6] = [
        CameraModel::SimplePinhole,
        CameraModel::Pinhole,
        CameraModel::SimpleRadial,
        CameraModel::Radial,
        CameraModel::OpenCv,
        CameraModel::FullOpenCv,
    ];

    /// COLMAP's name (`cameras.txt`).
    pub fn name(self) -> &'static str {
        match self {
            CameraModel::SimplePinhole => "SIMPLE_PINHOLE",
            CameraModel::Pinhole => "PINHOLE",
            CameraModel::SimpleRadial => "SIMPLE_RADIAL",
            CameraModel::Radial => "RADIAL",
            CameraModel::OpenCv => "OPENCV",
            CameraModel::FullOpenCv => "FULL_OPENCV",
        }
    }

    /// COLMAP's numeric id (`cameras.bin`).
    pub fn id(self) -> i32 {
        match self {
            CameraModel::SimplePinhole => 0,
            CameraModel::Pinhole => 1,
            CameraModel::SimpleRadial => 2,
            CameraModel::Radial => 3,
            CameraModel::OpenCv => 4,
            CameraModel::FullOpenCv => 6,
        }
    }

    /// The model called `name`, if trompe reads it.
    pub fn from_name(name: &str) -> Option<CameraModel> {
        Self::ALL.into_iter().find(|m| m.name() == name)
    }

    /// The model with COLMAP id `id`, if trompe reads it.
    pub fn from_id(id: i32) -> Option<CameraModel> {
        Self::ALL.into_iter().find(|m| m.id() == id)
    }

    /// How many parameters the model takes.
    pub fn param_count(self) -> usize {
        match self {
            CameraModel::SimplePinhole => 3,
            CameraModel::Pinhole => 4,
            CameraModel::SimpleRadial => 4,
            CameraModel::Radial => 5,
            CameraModel::OpenCv => 8,
            CameraModel::FullOpenCv => 12,
        }
    }
}

/// A camera's intrinsics: model, image size and parameters (validated: as many as the model
/// takes, all finite, focal lengths positive).
#[derive(Clone, Debug, PartialEq)]
pub struct Intrinsics {
    model: CameraModel,
    width: u32,
    height: u32,
    params: Vec<f64>,
}

/// Most Newton steps of an undistortion.
const UNDISTORT_STEPS: usize = 100;

impl Intrinsics {
    /// Intrinsics of `model` with `params` in COLMAP's order; `Err` says what is wrong.
    pub fn new(
        model: CameraModel,
        width: u32,
        height: u32,
        params: Vec<f64>,
    ) -> Result<Intrinsics, String> {
        if params.len() != model.param_count() {
            return Err(format!(
                "{} takes {} parameters, not {}",
                model.name(),
                model.param_count(),
                params.len()
            ));
        }
        if let Some(i) = params.iter().position(|p| !p.is_finite()) {
            return Err(format!("parameter {} is not finite", i + 1));
        }
        if width == 0 || height == 0 {
            return Err(format!("image size {width} × {height}"));
        }
        let c = Intrinsics {
            model,
            width,
            height,
            params,
        };
        let (fx, fy) = c.focal();
        if !(fx > 0.0 && fy > 0.0) {
            return Err(format!("focal length {fx} × {fy} is not positive"));
        }
        Ok(c)
    }

    /// An undistorted pinhole (`PINHOLE`) camera.
    pub fn pinhole(width: u32, height: u32, fx: f64, fy: f64, cx: f64, cy: f64) -> Intrinsics {
        Intrinsics {
            model: CameraModel::Pinhole,
            width,
            height,
            params: vec![fx, fy, cx, cy],
        }
    }

    /// The model.
    pub fn model(&self) -> CameraModel {
        self.model
    }

    /// The parameters, in COLMAP's order.
    pub fn params(&self) -> &[f64] {
        &self.params
    }

    /// Image size in pixels.
    pub fn size(&self) -> (u32, u32) {
        (self.width, self.height)
    }

    /// Focal lengths `(fx, fy)` in pixels.
    pub fn focal(&self) -> (f64, f64) {
        let p = &self.params;
        match self.model {
            CameraModel::SimplePinhole | CameraModel::SimpleRadial | CameraModel::Radial => {
                (p[0], p[0])
            }
            _ => (p[0], p[1]),
        }
    }

    /// Principal point `(cx, cy)` in pixels.
    pub fn principal_point(&self) -> (f64, f64) {
        let p = &self.params;
        match self.model {
            CameraModel::SimplePinhole | CameraModel::SimpleRadial | CameraModel::Radial => {
                (p[1], p[2])
            }
            _ => (p[2], p[3]),
        }
    }

    /// Whether the model has no distortion (or all its coefficients are zero).
    pub fn is_undistorted(&self) -> bool {
        let extra = match self.model {
            CameraModel::SimplePinhole | CameraModel::Pinhole => &[][..],
            CameraModel::SimpleRadial | CameraModel::Radial => &self.params[3..],
            _ => &self.params[4..],
        };
        extra.iter().all(|&k| k == 0.0)
    }

    /// The distorted normalised coordinates of undistorted ones (COLMAP's `Distortion` added).
    pub fn distort(&self, n: DVec2) -> DVec2 {
        n + self.distortion(n)
    }

    /// COLMAP's distortion offset `Δ(u, v)`: the distorted point is `n + Δ(n)`.
    fn distortion(&self, n: DVec2) -> DVec2 {
        let p = &self.params;
        let (u, v) = (n.x, n.y);
        let (u2, v2, uv) = (u * u, v * v, u * v);
        let r2 = u2 + v2;
        match self.model {
            CameraModel::SimplePinhole | CameraModel::Pinhole => DVec2::ZERO,
            CameraModel::SimpleRadial => n * (p[3] * r2),
            CameraModel::Radial => n * (p[3] * r2 + p[4] * r2 * r2),
            CameraModel::OpenCv => {
                let (k1, k2, p1, p2) = (p[4], p[5], p[6], p[7]);
                let radial = k1 * r2 + k2 * r2 * r2;
                DVec2::new(
                    u * radial + 2.0 * p1 * uv + p2 * (r2 + 2.0 * u2),
                    v * radial + 2.0 * p2 * uv + p1 * (r2 + 2.0 * v2),
                )
            }
            CameraModel::FullOpenCv => {
                let (k1, k2, p1, p2) = (p[4], p[5], p[6], p[7]);
                let (k3, k4, k5, k6) = (p[8], p[9], p[10], p[11]);
                let (r4, r6) = (r2 * r2, r2 * r2 * r2);
                let radial =
                    (1.0 + k1 * r2 + k2 * r4 + k3 * r6) / (1.0 + k4 * r2 + k5 * r4 + k6 * r6);
                DVec2::new(
                    u * radial + 2.0 * p1 * uv + p2 * (r2 + 2.0 * u2) - u,
                    v * radial + 2.0 * p2 * uv + p1 * (r2 + 2.0 * v2) - v,
                )
            }
        }
    }

    /// The pixel of normalised coordinates `n` (distortion applied).
    pub fn pixel_of(&self, n: DVec2) -> DVec2 {
        let d = self.distort(n);
        let ((fx, fy), (cx, cy)) = (self.focal(), self.principal_point());
        DVec2::new(fx * d.x + cx, fy * d.y + cy)
    }

    /// The normalised coordinates of a pixel (distortion removed by Newton's method on
    /// `n + Δ(n) = d`, to 1e-12 in normalised units, as COLMAP iterates); `None` where it does
    /// not converge (far outside the lens's valid field).
    pub fn normalized_of(&self, pixel: DVec2) -> Option<DVec2> {
        let ((fx, fy), (cx, cy)) = (self.focal(), self.principal_point());
        let d = DVec2::new((pixel.x - cx) / fx, (pixel.y - cy) / fy);
        if self.is_undistorted() {
            return Some(d);
        }
        let mut n = d;
        for _ in 0..UNDISTORT_STEPS {
            let f = self.distort(n) - d;
            if f.length() < 1e-12 {
                return Some(n);
            }
            // The Jacobian of n ↦ n + Δ(n), by central differences.
            let h = 1e-7 * (1.0 + n.length());
            let ju = (self.distort(n + DVec2::X * h) - self.distort(n - DVec2::X * h)) / (2.0 * h);
            let jv = (self.distort(n + DVec2::Y * h) - self.distort(n - DVec2::Y * h)) / (2.0 * h);
            let det = ju.x * jv.y - jv.x * ju.y;
            if det.abs() < 1e-12 || !det.is_finite() {
                return None;
            }
            let step = DVec2::new(
                (jv.y * f.x - jv.x * f.y) / det,
                (-ju.y * f.x + ju.x * f.y) / det,
            );
            n -= step;
            if !n.is_finite() {
                return None;
            }
        }
        (self.distort(n) - d).length().lt(&1e-9).then_some(n)
    }

    /// The camera of `model` with focal lengths and principal point `[fx, fy, cx, cy]` and the
    /// model's other parameters, `distortion`, in COLMAP's order after those (a model with one
    /// focal length needs `fx = fy`); `Err` says what is wrong.
    pub fn with_distortion(
        model: CameraModel,
        width: u32,
        height: u32,
        [fx, fy, cx, cy]: [f64; 4],
        distortion: &[f64],
    ) -> Result<Intrinsics, String> {
        let mut params = match model {
            CameraModel::SimplePinhole | CameraModel::SimpleRadial | CameraModel::Radial => {
                if fx != fy {
                    return Err(format!(
                        "{} has one focal length: fx = {fx} and fy = {fy} differ",
                        model.name()
                    ));
                }
                vec![fx, cx, cy]
            }
            CameraModel::Pinhole | CameraModel::OpenCv | CameraModel::FullOpenCv => {
                vec![fx, fy, cx, cy]
            }
        };
        let focal = params.len();
        if distortion.len() + focal != model.param_count() {
            return Err(format!(
                "{} takes {} distortion parameters, not {}",
                model.name(),
                model.param_count() - focal,
                distortion.len()
            ));
        }
        params.extend_from_slice(distortion);
        Intrinsics::new(model, width, height, params)
    }

    /// Where pixel `pixel` of this lens lands in its undistorted pinhole
    /// ([`Intrinsics::undistorted`]): the pinhole's pixel whose ray it sees along; `None` where
    /// undistortion does not converge.
    pub fn undistorted_pixel_of(&self, pixel: DVec2) -> Option<DVec2> {
        let n = self.normalized_of(pixel)?;
        let ((fx, fy), (cx, cy)) = (self.focal(), self.principal_point());
        Some(DVec2::new(fx * n.x + cx, fy * n.y + cy))
    }

    /// The undistorted pinhole of the same size, focal length and principal point: what a
    /// renderer that needs a pinhole draws, the view's image resampled to it by
    /// [`Intrinsics::normalized_of`]'s inverse.
    pub fn undistorted(&self) -> Intrinsics {
        let ((fx, fy), (cx, cy)) = (self.focal(), self.principal_point());
        Intrinsics::pinhole(self.width, self.height, fx, fy, cx, cy)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn undistortion_inverts_distortion() {
        let c = Intrinsics::new(
            CameraModel::OpenCv,
            320,
            240,
            vec![410.0, 395.0, 158.5, 121.25, -0.1, 0.03, 0.001, -0.0015],
        )
        .unwrap();
        for (x, y) in [(0.5, 0.5), (160.0, 120.0), (319.5, 239.5), (30.0, 200.0)] {
            let px = DVec2::new(x, y);
            let n = c.normalized_of(px).unwrap();
            assert!((c.pixel_of(n) - px).length() < 1e-6, "{px}");
        }
    }

    #[test]
    fn parameter_lists_are_checked() {
        assert!(Intrinsics::new(CameraModel::Radial, 4, 4, vec![1.0; 4]).is_err());
        assert!(Intrinsics::new(CameraModel::Pinhole, 4, 4, vec![1.0, f64::NAN, 0., 0.]).is_err());
        assert!(Intrinsics::new(CameraModel::Pinhole, 4, 4, vec![-1.0, 1., 0., 0.]).is_err());
        assert_eq!(CameraModel::from_id(6), Some(CameraModel::FullOpenCv));
        assert_eq!(CameraModel::from_name("FISHEYE"), None);
    }
}
