//! The impostor method (paper 1 §6): primary rays see the exact scene, and every ray a mirror or
//! glass object sends out into the open is answered by impostors of the diffuse objects, built
//! from that object's centre — a SPOC (§3) of an object it stands outside of, an orthographic
//! depth image along the normal of a flat one it stands over (a floor; the paper's grid is a
//! billboard), the six pinhole depth images of a cube map of any other object around it (a
//! room; the paper turns to the graph camera for whole environments) — or by the environment
//! where it misses them. An impostor's colour is the diffuse shading the tracer computes at its
//! texels, so where the impostors capture what a ray meets, the method agrees with `trace` to
//! their sampling; it differs where they do not.
//!
//! Mirrors and glass objects see one another exactly, through a BVH of them alone, and the
//! tracer shades what they see there (beyond the paper, whose reflectors see only impostors).
//! A device may draw the impostors' visibility images itself ([`ImpostorDrawer`]: a GPU's
//! rasterizer, as the paper built them); they are resolved as the library resolves its own.
//!
//! Invariants: pixels whose primary ray meets a diffuse object are the `trace` method's, exactly;
//! a diffuse object is seen in a mirror or through glass only as an impostor; the result does
//! not depend on the thread count.

use super::shading::{Shadows, albedo, lambert};
use super::trace::Tracer;
use super::{Mirrors, Progress, RenderError, Timings};
use crate::camera::Pinhole;
use crate::frame::Frame;
use crate::geom::{Mesh, Ray};
use crate::impostor::{Impostor, ImpostorBuilder, ImpostorCamera, SurfaceSample, ViewCamera};
use crate::memory::OverBudget;
use crate::scene::{Lighting, MazeObject, RenderSettings, Surface, View};
use crate::trace::{Bvh, Hit, RayQuery, SecondaryQuery};
use glam::{Affine3A, Mat4, Vec3};
use std::path::PathBuf;
use std::sync::Arc;

/// Impostor resolution (square) when none is asked for.
pub const DEFAULT_IMPOSTOR_RESOLUTION: u32 = 512;

/// A flat object is one whose bounding box is thinner than this fraction of its largest extent.
const FLAT: f32 = 0.01;

/// The answers of paper 1 §6's method to the rays mirrors and glass send out: per mirror or
/// glass object, impostors of the diffuse objects it sees (and, with [`Mirrors::Impostor`], of
/// the other mirrors, which carry their normals so the ray reflects on), and the specular
/// objects it sees exactly through a BVH of them alone; the nearer answer wins.
pub struct ReflectorImpostors {
    /// Per object id: the impostors its rays meet (empty for a diffuse object).
    per_object: Vec<Vec<Seen>>,
    /// Per object id: the specular objects its rays meet exactly (`None` for a diffuse object).
    exact: Vec<Option<Arc<ExactSpecular>>>,
}

/// One impostor a reflector's rays meet.
pub(super) struct Seen {
    /// The impostor, as built (shared between the reflectors that see it, and between frames).
    pub impostor: Arc<Impostor>,
    /// Where its object has moved since it was built (`None`: nowhere).
    pub placement: Option<Placement>,
    /// Its hits carry the impostor's colour (a diffuse object's); otherwise they carry none,
    /// and the tracer reflects on off the stored normal (a mirror's).
    pub radiance: bool,
}

/// The rigid motion that carries an impostor from where its object was when it was built to
/// where it is now: a ray is taken into the impostor's frame, and its hit back out.
#[derive(Clone, Copy, Debug)]
pub(super) struct Placement {
    now_from_built: Affine3A,
    built_from_now: Affine3A,
}

impl Placement {
    /// The motion `now_from_built` (rigid: rotation and translation), or `None` when it is the
    /// identity.
    pub fn of(now_from_built: Mat4) -> Option<Self> {
        if now_from_built == Mat4::IDENTITY {
            return None;
        }
        let now_from_built = Affine3A::from_mat4(now_from_built);
        Some(Self {
            now_from_built,
            built_from_now: now_from_built.inverse(),
        })
    }

    /// A point where it was built, now.
    pub fn point(&self, p: Vec3) -> Vec3 {
        self.now_from_built.transform_point3(p)
    }

    /// A direction where it was built, now (unit in, unit out: the motion is rigid).
    pub fn vector(&self, v: Vec3) -> Vec3 {
        self.now_from_built.transform_vector3(v)
    }
}

impl Seen {
    fn closest_hit(&self, ray: &Ray) -> Option<Hit> {
        let hit = match &self.placement {
            None => self.impostor.closest_hit(ray, f32::INFINITY)?,
            Some(m) => {
                let there = Ray::new(
                    m.built_from_now.transform_point3(ray.origin),
                    m.built_from_now.transform_vector3(ray.dir),
                );
                let h = self.impostor.closest_hit(&there, f32::INFINITY)?;
                Hit {
                    position: m.point(h.position),
                    normal: m.vector(h.normal),
                    geometric_normal: m.vector(h.geometric_normal),
                    ..h
                }
            }
        };
        Some(if self.radiance {
            hit
        } else {
            Hit {
                radiance: None,
                ..hit
            }
        })
    }
}

/// Specular objects seen exactly: a BVH of their meshes and their scene ids.
struct ExactSpecular {
    ids: Vec<u32>,
    bvh: Bvh,
}

impl ExactSpecular {
    fn new(view: &View, ids: Vec<u32>) -> Result<Arc<Self>, OverBudget> {
        let bvh = Bvh::build(
            ids.iter()
                .map(|&o| view.meshes[o as usize].clone())
                .collect(),
        )?;
        Ok(Arc::new(Self { ids, bvh }))
    }
}

impl ReflectorImpostors {
    /// Builds, for every mirror or glass object of `view`, `inputs.resolution²` impostors of
    /// the diffuse objects seen from its centre, shaded as the tracer shades them under
    /// `lighting` — or, for an object `inputs.baked` names a file for, that baked impostor,
    /// lit the same way, for every mirror and glass object — and, with
    /// [`Mirrors::Impostor`], impostors of the other mirrors.
    pub fn build(
        view: &View,
        lighting: &Lighting,
        inputs: ImpostorInputs<'_>,
        timings: &mut Timings,
    ) -> Result<Self, RenderError> {
        let resolution = inputs.resolution;
        // A size the maps can have, said as such rather than as a degenerate camera.
        crate::frame::check_size(u64::from(resolution), u64::from(resolution))?;
        let baked = if inputs.baked.iter().any(Option::is_some) {
            timings.time("load baked impostors", || load_baked(view, inputs.baked))?
        } else {
            Vec::new()
        };
        let per_object = timings.time("build impostors", || {
            reflector_impostors(view, lighting, &inputs, &baked)
        })?;
        Ok(timings.time("prepare walks, specular BVH", || {
            Self::assemble(view, per_object, inputs.mirrors)
        })?)
    }

    /// Wraps impostors made elsewhere (baked, or built with settings of one's own):
    /// `per_object[o]` are those object `o`'s rays meet, their hits carrying the impostors'
    /// colours; mirrors and glass of `view` see one another exactly (through a BVH of them,
    /// refused past the memory budget).
    pub fn from_impostors(view: &View, per_object: Vec<Vec<Impostor>>) -> Result<Self, OverBudget> {
        let per_object = per_object
            .into_iter()
            .map(|seen| {
                seen.into_iter()
                    .map(|impostor| Seen {
                        impostor: Arc::new(impostor),
                        placement: None,
                        radiance: true,
                    })
                    .collect()
            })
            .collect();
        Self::assemble(view, per_object, Mirrors::Exact)
    }

    /// The answers from the impostors each object's rays meet, `per_object`; the mirror and
    /// glass objects seen exactly as `mirrors` says.
    pub(super) fn assemble(
        view: &View,
        mut per_object: Vec<Vec<Seen>>,
        mirrors: Mirrors,
    ) -> Result<Self, OverBudget> {
        per_object.resize_with(view.surfaces.len(), Vec::new);
        for seen in per_object.iter().flatten() {
            seen.impostor.prepare_walks();
        }
        let specular = |o: u32| !matches!(view.surfaces[o as usize], Surface::Diffuse(_));
        let ids = 0..view.surfaces.len() as u32;
        let exact = match mirrors {
            // One BVH of every mirror and glass object, for all of them.
            Mirrors::Exact => {
                let all = ExactSpecular::new(view, ids.clone().filter(|&o| specular(o)).collect())?;
                ids.map(|o| specular(o).then(|| all.clone())).collect()
            }
            // Each sees itself and the glass exactly; the other mirrors are impostors.
            Mirrors::Impostor => {
                let glass = |o: u32| matches!(view.surfaces[o as usize], Surface::Glass { .. });
                ids.map(|r| {
                    specular(r)
                        .then(|| {
                            let seen = (0..view.surfaces.len() as u32)
                                .filter(|&o| o == r || glass(o))
                                .collect();
                            ExactSpecular::new(view, seen)
                        })
                        .transpose()
                })
                .collect::<Result<_, _>>()?
            }
        };
        Ok(Self { per_object, exact })
    }

    /// The impostors the rays of object `reflector` meet.
    pub fn of(&self, reflector: u32) -> impl Iterator<Item = &Impostor> {
        self.per_object
            .get(reflector as usize)
            .into_iter()
            .flatten()
            .map(|s| s.impostor.as_ref())
    }

    /// The impostors the rays of object `reflector` meet, each with where its object has moved
    /// since it was built and whether its hits carry its colour: what a device that walks the
    /// impostors itself needs (`trompe-gpu`).
    pub fn seen_by(&self, reflector: u32) -> impl Iterator<Item = SeenImpostor<'_>> {
        self.per_object
            .get(reflector as usize)
            .into_iter()
            .flatten()
            .map(|s| SeenImpostor {
                impostor: s.impostor.as_ref(),
                now_from_built: s
                    .placement
                    .map_or(Mat4::IDENTITY, |p| Mat4::from(p.now_from_built)),
                radiance: s.radiance,
            })
    }

    /// The objects the rays of object `reflector` meet exactly (through a BVH of them alone),
    /// by scene id; empty for a diffuse object.
    pub fn seen_exactly_by(&self, reflector: u32) -> &[u32] {
        self.exact
            .get(reflector as usize)
            .and_then(Option::as_ref)
            .map_or(&[], |e| e.ids.as_slice())
    }
}

/// One impostor a mirror or glass object's rays meet, as [`ReflectorImpostors::seen_by`] lists
/// it.
#[derive(Clone, Copy, Debug)]
pub struct SeenImpostor<'a> {
    /// The impostor, in the frame its object was built in.
    pub impostor: &'a Impostor,
    /// The rigid motion from where its object was when it was built to where it is now (the
    /// identity when it has not moved).
    pub now_from_built: Mat4,
    /// Whether its hits carry its colour (a diffuse object's); otherwise the surface it stores
    /// is shaded as a mirror (its object's surface).
    pub radiance: bool,
}

impl SecondaryQuery for ReflectorImpostors {
    fn secondary_hit(&self, reflector: u32, ray: &Ray) -> Option<Hit> {
        let seen = self
            .per_object
            .get(reflector as usize)
            .into_iter()
            .flatten()
            .filter_map(|s| s.closest_hit(ray));
        let exact = self
            .exact
            .get(reflector as usize)
            .and_then(Option::as_ref)
            .and_then(|e| {
                let h = e.bvh.closest_hit(ray, f32::INFINITY)?;
                Some(Hit {
                    object: e.ids[h.object as usize],
                    ..h
                })
            });
        seen.chain(exact).min_by(|a, b| a.t.total_cmp(&b.t))
    }
}

/// What draws impostors' visibility images elsewhere — a GPU's rasterizer (`trompe-gpu`) — for
/// the impostor methods to resolve as they resolve their own ([`crate::impostor::resolve_drawn`],
/// paper 1 §3.1); the cameras it does not draw are built by the library.
pub trait ImpostorDrawer: Send + Sync {
    /// The visibility image of `mesh` through `camera` (through a graph camera, with each
    /// texel's frustum), or `None` where it does not draw this camera; `Err` with the device's
    /// reason where it failed.
    fn draw(
        &self,
        camera: &ImpostorCamera,
        mesh: &Mesh,
    ) -> Option<Result<crate::impostor::DrawnImage, String>>;
}

impl std::fmt::Debug for dyn ImpostorDrawer + '_ {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("ImpostorDrawer")
    }
}

/// What the impostor method is given besides the view: the resolution of the impostors it
/// builds, and per object id the baked impostor to use instead (`None`, or a slice shorter
/// than the objects: build one).
#[derive(Clone, Copy, Debug)]
pub struct ImpostorInputs<'a> {
    /// Texels a side of every impostor built.
    pub resolution: u32,
    /// Per object id, a baked impostor's sidecar.
    pub baked: &'a [Option<PathBuf>],
    /// Per object id, the maze plan the object is made from: a mirror or glass object inside
    /// the maze sees it through the maze's graph camera.
    pub mazes: &'a [Option<MazeObject>],
    /// What shadows the impostors' texels as the tracer shadows what it hits (`None`: lit
    /// unshadowed).
    pub shadows: Option<Shadows<'a>>,
    /// Planar (pinhole) depth images where a SPOC would be built: paper 1's Fig. 6 baseline.
    pub pinhole: bool,
    /// How the eye's refractions into glass are found.
    pub refraction: super::Refraction,
    /// How mirrors see the other mirrors.
    pub mirrors: Mirrors,
    /// What finds the surfaces the eye sees.
    pub primary: super::Primary,
    /// What draws impostors elsewhere (`None`: the library builds every one).
    pub drawer: Option<&'a dyn ImpostorDrawer>,
}

impl ImpostorInputs<'_> {
    /// Impostors of `resolution²` texels, built for every object, lit unshadowed, through
    /// SPOCs; refractions exact; mirrors seen exactly.
    pub fn new(resolution: u32) -> Self {
        ImpostorInputs {
            resolution,
            baked: &[],
            mazes: &[],
            shadows: None,
            pinhole: false,
            refraction: super::Refraction::Exact,
            mirrors: Mirrors::Exact,
            primary: super::Primary::Traced,
            drawer: None,
        }
    }
}

/// What stands in for a scene's objects under the impostor methods, per object id: a baked
/// impostor the scene names, and the maze plan an object is made from.
#[derive(Clone, Debug, Default)]
pub struct StandIns {
    /// Per object id, a baked impostor's sidecar.
    pub baked: Vec<Option<PathBuf>>,
    /// Per object id, the maze it is made from.
    pub mazes: Vec<Option<MazeObject>>,
}

impl StandIns {
    /// The stand-ins `scene` names.
    pub fn of(scene: &crate::scene::Scene) -> Self {
        Self {
            baked: scene.objects.iter().map(|o| o.impostor.clone()).collect(),
            mazes: scene.objects.iter().map(|o| o.maze.clone()).collect(),
        }
    }
}

/// Renders `view` by the impostor method.
pub fn render_impostor(
    view: &View,
    lighting: &Lighting,
    settings: &RenderSettings,
    inputs: ImpostorInputs<'_>,
    progress: &dyn Progress,
    timings: &mut Timings,
) -> Result<Frame, RenderError> {
    let bvh = timings.time("build BVH", || Bvh::build(view.meshes.clone()))?;
    let inputs = ImpostorInputs {
        shadows: Some(Shadows {
            occluders: &bvh,
            epsilon: settings.ray_epsilon,
        }),
        ..inputs
    };
    let secondary = ReflectorImpostors::build(view, lighting, inputs, timings)?;
    let tracer = Tracer {
        view,
        primary: &bvh,
        secondary: &secondary,
        lighting,
        settings,
    };
    super::trace_frame(
        &tracer,
        (inputs.refraction, inputs.primary),
        progress,
        timings,
    )
}

/// The baked impostors `files` names, per object id, each checked against the object as the
/// view places it, its object id set to the object's; their colours are the albedo they were
/// baked with, for [`lit`] to light.
pub(super) fn load_baked(
    view: &View,
    files: &[Option<PathBuf>],
) -> Result<Vec<Option<Impostor>>, RenderError> {
    let mut out = Vec::with_capacity(files.len());
    for (object, file) in files.iter().enumerate() {
        let (Some(path), Some(mesh)) = (file, view.meshes.get(object)) else {
            out.push(None);
            continue;
        };
        let mut imp = crate::impostor::file::load(path)
            .map_err(|source| RenderError::BakedImpostor { object, source })?;
        if !imp.was_built_from(mesh) {
            let (ib, mb) = (imp.bounds(), mesh.bounds());
            return Err(RenderError::BakedMismatch {
                object,
                path: path.clone(),
                impostor_box: [ib.min.to_array(), ib.max.to_array()],
                object_box: [mb.min.to_array(), mb.max.to_array()],
            });
        }
        // The object's id in this scene, whatever id it was baked with.
        imp.set_object_id(object as u32);
        imp.prepare_walks();
        out.push(Some(imp));
    }
    Ok(out)
}

/// `unlit` — an impostor whose colours are albedo — lit as the tracer lights what it hits,
/// where `placement` has carried it (the diffuse shading under `lighting`, the normal turned
/// toward the impostor's viewpoint, the light's shadow ray through `shadows`).
pub(super) fn lit(
    unlit: &Impostor,
    placement: Option<Placement>,
    lighting: &Lighting,
    shadows: Option<Shadows<'_>>,
) -> Impostor {
    let mut imp = unlit.clone();
    let eye = imp.camera().viewpoint().as_vec3();
    imp.relight(|albedo, normal, position| {
        let (eye, normal, position) = match &placement {
            None => (eye, normal, position),
            Some(m) => (m.point(eye), m.vector(normal), m.point(position)),
        };
        let n = toward(normal, eye - position);
        lambert(albedo, n, lighting, |l| {
            shadows.is_none_or(|s| s.lit(position, n, l))
        })
    });
    imp
}

/// Whether `p` is in the box `b`.
fn inside(b: crate::geom::Aabb, p: Vec3) -> bool {
    (p.cmpge(b.min) & p.cmple(b.max)).all()
}

/// `n`, or `−n` when it faces away from `to`.
fn toward(n: Vec3, to: Vec3) -> Vec3 {
    if n.dot(to) < 0.0 { -n } else { n }
}

/// Whether the impostor method answers the rays of mirror and glass objects meeting object `o`
/// with impostors of it: a diffuse object always; a mirror with [`Mirrors::Impostor`].
pub(super) fn seen_as_impostor(view: &View, o: usize, mirrors: Mirrors) -> bool {
    match view.surfaces[o] {
        Surface::Diffuse(_) => true,
        Surface::Mirror { .. } => mirrors == Mirrors::Impostor,
        Surface::Glass { .. } => false,
    }
}

/// The impostors of object `o` that the rays of mirror or glass object `r` meet, built from
/// `r`'s centre: their colours the albedo of a diffuse object (for [`lit`] to light), black
/// for a mirror, whose impostors keep only its surface. Those `inputs.drawer` draws are
/// resolved from its images, and counted in `drawn`.
pub(super) fn build_unlit(
    view: &View,
    (r, o): (usize, usize),
    inputs: &ImpostorInputs<'_>,
    builder: &mut ImpostorBuilder,
    drawn: &mut usize,
) -> Result<Vec<Impostor>, RenderError> {
    let outside = if inputs.pinhole {
        ViewCamera::Pinhole
    } else {
        ViewCamera::Spoc(None)
    };
    let reflector = view.meshes[r].bounds();
    let (eye, region) = (reflector.center(), reflector.radius() as f64);
    let (mesh, surface) = (&view.meshes[o], &view.surfaces[o]);
    let err = |reason| RenderError::Impostor {
        object: o,
        reflector: r,
        reason,
    };
    let cameras = match inputs.mazes.get(o).and_then(Option::as_ref) {
        // A reflector in a maze sees it through the maze's graph camera (paper 1 §5).
        Some(m) if inside(mesh.bounds(), eye) => vec![ImpostorCamera::Graph(
            m.maze
                .graph_camera(inputs.resolution, &m.path)
                .map_err(|_| err("its maze's graph camera could not be built"))?,
        )],
        _ => impostor_cameras(mesh, eye, region, inputs.resolution, outside).map_err(err)?,
    };
    let diffuse = matches!(surface, Surface::Diffuse(_));
    let color = |s: &SurfaceSample| {
        if diffuse {
            albedo(mesh, surface, s.triangle, s.uv)
        } else {
            Vec3::ZERO
        }
    };
    cameras
        .into_iter()
        .map(|camera| {
            let imp = match inputs.drawer.and_then(|d| d.draw(&camera, mesh)) {
                Some(image) => {
                    let failed = |reason: String| RenderError::Drawn {
                        object: o,
                        reflector: r,
                        reason,
                    };
                    let image = image.map_err(failed)?;
                    *drawn += 1;
                    crate::impostor::resolve_drawn(camera, (mesh, o as u32), &color, &image)
                        .map_err(|e| failed(e.to_string()))?
                }
                None => builder.build(camera, mesh, o as u32, &color)?,
            };
            imp.prepare_walks();
            Ok(imp)
        })
        .collect()
}

/// Per object of `view`: for a mirror or glass object, impostors of every object it sees as
/// one ([`seen_as_impostor`]), built from its centre and lit, or the baked impostor `baked`
/// holds for it; nothing for a diffuse object.
fn reflector_impostors(
    view: &View,
    lighting: &Lighting,
    inputs: &ImpostorInputs<'_>,
    baked: &[Option<Impostor>],
) -> Result<Vec<Vec<Seen>>, RenderError> {
    // A baked impostor is lit once and seen by every mirror and glass object.
    let baked: Vec<Option<Arc<Impostor>>> = baked
        .iter()
        .map(|b| {
            b.as_ref()
                .map(|imp| Arc::new(lit(imp, None, lighting, inputs.shadows)))
        })
        .collect();
    let mut out = Vec::with_capacity(view.surfaces.len());
    // One builder for all: its working memory is allocated once, not once per impostor.
    let mut builder = ImpostorBuilder::new();
    for (r, surface) in view.surfaces.iter().enumerate() {
        let mut seen = Vec::new();
        if matches!(surface, Surface::Diffuse(_)) {
            out.push(seen);
            continue;
        }
        for o in (0..view.surfaces.len()).filter(|&o| o != r) {
            if !seen_as_impostor(view, o, inputs.mirrors) {
                continue;
            }
            let radiance = matches!(view.surfaces[o], Surface::Diffuse(_));
            if let Some(Some(imp)) = baked.get(o) {
                seen.push(Seen {
                    impostor: imp.clone(),
                    placement: None,
                    radiance,
                });
                continue;
            }
            for unlit in build_unlit(view, (r, o), inputs, &mut builder, &mut 0)? {
                let impostor = if radiance {
                    lit(&unlit, None, lighting, inputs.shadows)
                } else {
                    unlit
                };
                seen.push(Seen {
                    impostor: Arc::new(impostor),
                    placement: None,
                    radiance,
                });
            }
        }
        out.push(seen);
    }
    Ok(out)
}

/// The cameras of the impostors the impostor method builds of `mesh` for the mirror or glass
/// object `reflector` (from the reflector's centre, for rays from within its bounding radius: a
/// SPOC, a parallel projection of a flat object, or a cube map of one around it): what to bake through so that a baked impostor is the one it would build.
pub fn placed_cameras(
    mesh: &Mesh,
    reflector: &Mesh,
    resolution: u32,
) -> Result<Vec<ImpostorCamera>, &'static str> {
    let b = reflector.bounds();
    impostor_cameras(
        mesh,
        b.center(),
        b.radius() as f64,
        resolution,
        ViewCamera::Spoc(None),
    )
}

/// The cameras of the impostors of `mesh` seen from `eye`, whose secondary rays come from a
/// region of radius `region`: a camera of kind `outside` (a SPOC, or a pinhole for the planar
/// baseline) framed on the mesh when the eye is outside its bounding sphere; for a flat mesh the eye stands over, a parallel projection along its normal, which
/// captures all of it; for an object around the eye (a room, or an object the reflector stands
/// in the bounding sphere of), the six 90° pinholes of a cube map at the eye, which together
/// see everything visible from it.
fn impostor_cameras(
    mesh: &Mesh,
    eye: Vec3,
    region: f64,
    resolution: u32,
    outside: ViewCamera,
) -> Result<Vec<ImpostorCamera>, &'static str> {
    let b = mesh.bounds();
    let (center, radius) = (b.center(), b.radius());
    let fitted = |kind, from| {
        ImpostorCamera::fitted(
            kind,
            from,
            center,
            radius,
            region,
            resolution,
            &mesh.positions,
        )
    };
    let err = |_| "its impostor camera is degenerate";
    if eye.distance(center) > radius * 1.001 {
        return Ok(vec![fitted(outside, eye).map_err(err)?]);
    }
    let extent = b.extent();
    let thin = extent.min_position();
    if extent[thin] > FLAT * extent.max_element() {
        return cube_cameras(eye, radius, resolution);
    }
    let mut normal = Vec3::ZERO;
    normal[thin] = if eye[thin] < center[thin] { -1.0 } else { 1.0 };
    Ok(vec![
        fitted(ViewCamera::Orthographic, center + normal * (2.0 * radius)).map_err(err)?,
    ])
}

/// The six faces of a cube map centred on `eye` (90° square pinholes along ±x, ±y, ±z), near
/// planes a hair in front of the eye, for an object of bounding radius `radius` around it.
fn cube_cameras(
    eye: Vec3,
    radius: f32,
    resolution: u32,
) -> Result<Vec<ImpostorCamera>, &'static str> {
    let axes = [Vec3::X, -Vec3::X, Vec3::Y, -Vec3::Y, Vec3::Z, -Vec3::Z];
    axes.iter()
        .map(|&a| {
            let up = if a.y != 0.0 { Vec3::Z } else { Vec3::Y };
            let face = Pinhole::look_at(eye, eye + a, up, 90.0, resolution, resolution)
                .map_err(|_| "its cube-map impostor camera is degenerate")?;
            Ok(ImpostorCamera::Pinhole(
                face.with_near(radius.max(f32::MIN_POSITIVE) as f64 * 1e-4),
            ))
        })
        .collect()
}
