//! A mesh textured from photographs on a device: a COLMAP model's calibrated views seen through
//! their depth maps ([`crate::views`]), or a master encoding ([`crate::master`], "Master
//! Texture" §4), uploaded once where a GPU is given and blended through any camera with any
//! weighting; blended by the library ([`trompe::views::blend`], [`trompe::master::render`]) on
//! the CPU without one. The viewer's photograph modes run on it.
//!
//! Invariants: a change of weighting remakes the blend's tables and shader, never the uploaded
//! images; [`TexturedMesh::render_on_cpu`] is the CPU twin of every frame, whatever the device.

use crate::device::{Gpu, GpuError};
use crate::master::GpuMasters;
use crate::methods::DeviceError;
use crate::views::GpuViews;
use trompe::camera::Pinhole;
use trompe::frame::{Image, Rgba};
use trompe::geom::Mesh;
use trompe::master::layout::Layout;
use trompe::texturing::{Blend, BlendSettings};
use trompe::views::CalibratedView;
use trompe::views::visibility::DepthMap;

/// The photographs that texture a mesh.
#[derive(Clone, Copy)]
pub enum PhotoSource<'a> {
    /// Calibrated views (their images loaded) and their depth maps, one a view
    /// ([`DepthMap::of_all`]).
    Views {
        /// The views.
        views: &'a [CalibratedView],
        /// Their depth maps.
        depth: &'a [DepthMap],
    },
    /// A master encoding: its layout, its views' cameras and one master texture a view.
    Masters {
        /// The packing map of the mesh's faces.
        layout: &'a Layout,
        /// The views' cameras.
        cameras: &'a [Pinhole],
        /// The master textures.
        masters: &'a [Image<Rgba>],
    },
}

impl PhotoSource<'_> {
    /// The photographs' cameras (undistorted pinholes), in order.
    pub fn cameras(&self) -> Vec<Pinhole> {
        match self {
            PhotoSource::Views { views, .. } => views.iter().map(|v| v.pinhole()).collect(),
            PhotoSource::Masters { cameras, .. } => cameras.to_vec(),
        }
    }

    /// What the photographs are: "views" or "masters".
    pub fn name(&self) -> &'static str {
        match self {
            PhotoSource::Views { .. } => "views",
            PhotoSource::Masters { .. } => "masters",
        }
    }
}

/// The photographs, and what a GPU holds of them.
enum Held<'a> {
    Views {
        views: &'a [CalibratedView],
        depth: &'a [DepthMap],
        gpu: Option<GpuViews<'a>>,
    },
    Masters {
        layout: &'a Layout,
        cameras: &'a [Pinhole],
        masters: &'a [Image<Rgba>],
        gpu: Option<GpuMasters<'a>>,
    },
}

/// A mesh and the photographs that texture it, on the GPU where one is given (uploaded once),
/// else on the CPU.
pub struct TexturedMesh<'a> {
    mesh: &'a Mesh,
    held: Held<'a>,
    settings: BlendSettings,
}

impl<'a> TexturedMesh<'a> {
    /// `mesh` textured from `source` with `settings`, uploaded to `gpu` if given. Refuses what
    /// does not fit (masters of another mesh, cameras and masters that do not pair) and, on
    /// the GPU, what its blend does not do, before any frame.
    pub fn new(
        gpu: Option<&'a Gpu>,
        mesh: &'a Mesh,
        source: PhotoSource<'a>,
        settings: &BlendSettings,
    ) -> Result<Self, DeviceError> {
        let held = match source {
            PhotoSource::Views { views, depth } => Held::Views {
                views,
                depth,
                gpu: gpu
                    .map(|gpu| GpuViews::new(gpu, mesh, (views, depth), settings, None))
                    .transpose()?,
            },
            PhotoSource::Masters {
                layout,
                cameras,
                masters,
            } => {
                trompe::master::render::check(mesh, layout, cameras, masters)?;
                let upload = |gpu| GpuMasters::new(gpu, mesh, (layout, cameras, masters), settings);
                Held::Masters {
                    layout,
                    cameras,
                    masters,
                    gpu: gpu.map(upload).transpose()?,
                }
            }
        };
        Ok(Self {
            mesh,
            held,
            settings: *settings,
        })
    }

    /// The photographs.
    pub fn source(&self) -> PhotoSource<'a> {
        match self.held {
            Held::Views { views, depth, .. } => PhotoSource::Views { views, depth },
            Held::Masters {
                layout,
                cameras,
                masters,
                ..
            } => PhotoSource::Masters {
                layout,
                cameras,
                masters,
            },
        }
    }

    /// The blend's settings.
    pub fn settings(&self) -> &BlendSettings {
        &self.settings
    }

    /// Whether frames are blended on the GPU.
    pub fn on_gpu(&self) -> bool {
        match &self.held {
            Held::Views { gpu, .. } => gpu.is_some(),
            Held::Masters { gpu, .. } => gpu.is_some(),
        }
    }

    /// Blends with `settings` from now on; on the GPU, the blend's tables are made again (the
    /// photographs stay uploaded), and what its blend does not do is refused, the settings
    /// unchanged.
    pub fn set_settings(&mut self, settings: &BlendSettings) -> Result<(), DeviceError> {
        if *settings == self.settings {
            return Ok(());
        }
        match &mut self.held {
            Held::Views {
                views,
                depth,
                gpu: Some(gpu),
            } => gpu.reweigh(&[self.mesh], (views, Some(depth)), settings)?,
            Held::Masters {
                layout,
                cameras,
                masters,
                gpu: Some(gpu),
            } => gpu.reweigh(self.mesh, (layout, cameras, masters), settings)?,
            _ => {}
        }
        self.settings = *settings;
        Ok(())
    }

    /// The mesh through `camera`: the image and its pixels' counts.
    pub fn render(&self, camera: &Pinhole) -> Result<Blend, DeviceError> {
        match &self.held {
            Held::Views { gpu: Some(gpu), .. } => Ok(gpu.render(camera)?),
            Held::Masters { gpu: Some(gpu), .. } => Ok(gpu.render(camera)?),
            _ => self.render_on_cpu(camera),
        }
    }

    /// The mesh through `camera`, blended by the library on the CPU: every frame's twin.
    pub fn render_on_cpu(&self, camera: &Pinhole) -> Result<Blend, DeviceError> {
        let s = &self.settings;
        match self.held {
            Held::Views { views, depth, .. } => Ok(trompe::views::blend::render(
                camera, self.mesh, views, depth, s, None,
            )
            .map_err(GpuError::from)?),
            Held::Masters {
                layout,
                cameras,
                masters,
                ..
            } => Ok(trompe::master::render::render(
                camera, self.mesh, layout, cameras, masters, s,
            )?),
        }
    }
}
