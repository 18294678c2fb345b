//! The viewer's camera: flown or orbited around a target, levelled to the world's up (beyond the
//! papers: how a user moves through what they show).
//!
//! Invariant: the camera never rolls: its image's rows stay square to the world's up.

use glam::Vec3;
use trompe::camera::Pinhole;

/// Radians a pixel of mouse motion turns the camera.
pub const LOOK_PER_PIXEL: f32 = 0.003;
/// Factor a wheel notch multiplies the speed by.
pub const SPEED_PER_NOTCH: f32 = 1.2;

/// A camera flown or orbited around a target.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FlyCamera {
    /// Eye.
    pub eye: Vec3,
    /// Radians about the world's up; 0 looks along −z levelled (along −z where up is +y; along
    /// +x where up is ±z).
    pub yaw: f32,
    /// Radians above the horizon.
    pub pitch: f32,
    /// What orbit mode turns around.
    pub target: Vec3,
    /// Orbiting (else flying).
    pub orbit: bool,
    /// Full vertical field of view, degrees.
    pub fov_y: f64,
    /// Near-plane distance.
    pub near: f64,
    /// The world's up (unit): yaw turns about it, pitch rises towards it.
    pub up: Vec3,
}

impl FlyCamera {
    /// Looking from `eye` at `target` with `up` the world's up (+y when it is not a direction),
    /// with the near plane at `near`.
    pub fn looking_at(eye: Vec3, target: Vec3, up: Vec3, fov_y: f64, near: f64) -> Self {
        let mut camera = Self {
            eye,
            yaw: 0.0,
            pitch: 0.0,
            target,
            orbit: false,
            fov_y,
            near,
            up: up.try_normalize().unwrap_or(Vec3::Y),
        };
        let (ahead, right) = camera.level();
        let d = (target - eye).try_normalize().unwrap_or(ahead);
        camera.yaw = d.dot(right).atan2(d.dot(ahead));
        camera.pitch = d.dot(camera.up).clamp(-1.0, 1.0).asin();
        camera
    }

    /// The level directions of yaw 0 (−z where up is +y) and of the right hand (+x there).
    pub(super) fn level(&self) -> (Vec3, Vec3) {
        let up = self.up;
        let flat = |v: Vec3| (v - up * up.dot(v)).try_normalize();
        let ahead = flat(Vec3::NEG_Z)
            .or_else(|| flat(Vec3::X))
            .unwrap_or(Vec3::NEG_Z);
        (ahead, ahead.cross(up))
    }

    /// The unit view direction.
    pub fn direction(&self) -> Vec3 {
        let (sy, cy) = self.yaw.sin_cos();
        let (sp, cp) = self.pitch.sin_cos();
        let (ahead, right) = self.level();
        (ahead * cy + right * sy) * cp + self.up * sp
    }

    /// The pinhole of `w × h` pixels.
    pub fn pinhole(&self, (w, h): (u32, u32)) -> Result<Pinhole, trompe::camera::CameraError> {
        Ok(Pinhole::look_at(
            self.eye,
            self.eye + self.direction(),
            self.up,
            self.fov_y,
            w,
            h,
        )?
        .with_near(self.near))
    }

    pub(super) fn turn(&mut self, dx: f32, dy: f32) {
        let limit = 89f32.to_radians();
        self.yaw += dx * LOOK_PER_PIXEL;
        self.pitch = (self.pitch - dy * LOOK_PER_PIXEL).clamp(-limit, limit);
        if self.orbit {
            let distance = self.eye.distance(self.target);
            self.eye = self.target - self.direction() * distance;
        }
    }
}
