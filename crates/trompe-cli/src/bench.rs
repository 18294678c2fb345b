//! Benchmark workloads shared by `cargo bench` (criterion, `benches/`) and `trompe bench`: each
//! is timed beside a peer measured in the same run, so figures come with a ratio.
//!
//! Foundation workloads: rasterizer throughput on the 56k-triangle bunny (peer: a `memcpy` of the
//! bytes the rasterizer writes); BVH build; primary and incoherent (reflected) rays per second
//! through the BVH (peer: brute force over every triangle, on a sample of the same rays).
//!
//! Impostor workloads: SPOC impostor construction beside pinhole rasterizations of the same
//! mesh, for the bunny and for a textured mesh; SPOC walks per resolution; graph-camera
//! impostor construction of a maze with bunnies in its corridors beside a rasterization
//! through the camera's root.
//!
//! Relief workloads ([`relief`]): the pre-warp beside a copy of its texel buffers, ray-traced
//! impostor generation beside rasterizing the same image, a walk's frame beside direct
//! rasterization and ray tracing.
//!
//! Invariant: a timer stops before what it timed is freed, for a workload and its peer alike
//! (a fresh SPOC impostor's maps are 6.3 MB at 512², and returning them to the system is not
//! building them).

pub mod gpu;
pub mod hybrid;
pub mod layers;
pub mod master;
pub mod methods;
pub mod octahedral;
pub mod reflect;
pub mod relief;
pub mod texturing;
pub mod walks;

use glam::Vec3;
use rayon::prelude::*;
use std::sync::Arc;
use std::time::{Duration, Instant};
use trompe::camera::Pinhole;
use trompe::frame::envmap::EnvMap;
use trompe::frame::{Frame, FrameError};
use trompe::geom::{Mesh, Ray};
use trompe::raster::{ItemId, NoAttributes, RasterStats, RasterTarget, rasterize};
use trompe::render::{RenderError, Timings, render_raster};
use trompe::scene::{Lighting, RenderSettings, Surface, View};
use trompe::trace::{BruteForce, Bvh, RayQuery};

/// The repository's root, where `assets/` and `scenes/` are: for `cargo bench`, run from a
/// checkout.
pub fn repo_root() -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// A camera framing `mesh` ([`trompe::eval::fixtures::framing_camera`]).
///
/// # Panics
/// On a mesh whose box is not finite or a size of 0: benchmarks run on meshes that loaded.
pub fn framing_camera(mesh: &Mesh, size: u32) -> Pinhole {
    trompe::eval::fixtures::framing_camera(mesh, size).expect("a valid framing")
}

/// Runs `f` repeatedly for at least `min_time` (and at least once); returns the median duration.
/// What `f` returns is dropped after its clock stops: a build is timed, not the freeing of what
/// it built (criterion's `iter_with_large_drop`).
pub fn time_median<T>(min_time: Duration, mut f: impl FnMut() -> T) -> Duration {
    let mut samples = Vec::new();
    let start = Instant::now();
    while samples.is_empty() || (start.elapsed() < min_time && samples.len() < 1000) {
        let t = Instant::now();
        let output = f();
        samples.push(t.elapsed());
        drop(output);
    }
    samples.sort();
    samples[samples.len() / 2]
}

/// Median times of `a` and `b`, run alternately (`a`, `b`, `a`, `b` …) for at least `min_time`
/// in all: a workload and its peer see the same machine, so their ratio holds steady on a
/// noisy one where two separate medians drift apart. As in [`time_median`], what each returns
/// is dropped after its clock stops.
pub fn time_pair_median<A, B>(
    min_time: Duration,
    mut a: impl FnMut() -> A,
    mut b: impl FnMut() -> B,
) -> (Duration, Duration) {
    let never = pair_medians(
        min_time,
        || Ok::<_, std::convert::Infallible>(a()),
        || Ok(b()),
    );
    match never {
        Ok(medians) => medians,
        Err(never) => match never {},
    }
}

/// [`time_pair_median`] of two workloads that can fail (a build refused by the memory budget):
/// the first failure ends the timing and is returned.
pub fn try_time_pair_median<A, B, E, F>(
    min_time: Duration,
    mut a: impl FnMut() -> Result<A, E>,
    mut b: impl FnMut() -> Result<B, F>,
) -> Result<(Duration, Duration), BenchError>
where
    BenchError: From<E> + From<F>,
{
    pair_medians(
        min_time,
        || a().map_err(BenchError::from),
        || b().map_err(BenchError::from),
    )
}

fn pair_medians<A, B, E>(
    min_time: Duration,
    mut a: impl FnMut() -> Result<A, E>,
    mut b: impl FnMut() -> Result<B, E>,
) -> Result<(Duration, Duration), E> {
    let mut samples = (Vec::new(), Vec::new());
    let start = Instant::now();
    while samples.0.is_empty() || (start.elapsed() < min_time && samples.0.len() < 1000) {
        let t = Instant::now();
        let output = a()?;
        samples.0.push(t.elapsed());
        drop(output);
        let t = Instant::now();
        let output = b()?;
        samples.1.push(t.elapsed());
        drop(output);
    }
    samples.0.sort();
    samples.1.sort();
    let n = samples.0.len();
    Ok((samples.0[n / 2], samples.1[n / 2]))
}

/// The pinhole a pinhole impostor of the sphere (`center`, `radius`) seen from `eye` has,
/// `size²` pixels (`None` if the eye is inside the sphere).
pub fn framed_pinhole(eye: Vec3, center: Vec3, radius: f32, size: u32) -> Option<Pinhole> {
    use trompe::impostor::{ImpostorCamera, ViewCamera};
    match ImpostorCamera::around(ViewCamera::Pinhole, eye, center, radius, 0.0, size) {
        Ok(ImpostorCamera::Pinhole(p)) => Some(p),
        _ => None,
    }
}

/// Pixel centres `mesh` covers through `camera` (before the depth test).
pub fn fragments_through<P: trompe::camera::Projection>(camera: &P, mesh: &Mesh) -> u64 {
    rasterize(camera, &[mesh], &NoAttributes, ()).map_or(0, |(_, stats)| stats.fragments)
}

/// Rasterizes `mesh` through `camera` into depth and item buffers; returns pixels written.
pub fn raster_once(camera: &Pinhole, mesh: &Mesh) -> Result<u64, FrameError> {
    Ok(plain_raster(camera, mesh)?.1.written)
}

/// Rasterizes `mesh` through `camera` into depth and item buffers (the plain rasterization
/// peers), returning them, so a timer can leave their freeing out as it does a build's.
pub fn plain_raster(
    camera: &Pinhole,
    mesh: &Mesh,
) -> Result<(RasterTarget<()>, RasterStats), FrameError> {
    rasterize(camera, &[mesh], &NoAttributes, ())
}

/// The raster render method's view of `mesh` alone (diffuse, its own materials) through
/// `camera`, lit by a grey sky (no sun, so no shadow rays and no BVH): what rendering the
/// object's image with a pinhole costs — a frame of colour, distance, normals and ids, the maps
/// an impostor holds.
pub fn raster_view(camera: &Pinhole, mesh: &Mesh) -> (View, Lighting) {
    let view = View {
        lens: None,
        camera: camera.clone(),
        meshes: vec![Arc::new(mesh.clone())],
        surfaces: vec![Surface::Diffuse(None)],
    };
    let lighting = Lighting {
        environment: EnvMap::constant(Vec3::splat(0.3)),
        light: None,
    };
    (view, lighting)
}

/// Renders a [`raster_view`] by the raster method.
pub fn render_raster_once((view, lighting): &(View, Lighting)) -> Result<Frame, RenderError> {
    let mut timings = Timings::default();
    let settings = RenderSettings {
        max_depth: 1,
        time: 0.0,
        ray_epsilon: 1e-4,
    };
    render_raster(view, lighting, &settings, &(), &mut timings)
}

/// The bytes a depth + item rasterization writes, copied once (the raster peer).
pub fn memcpy_frame(src: &[u8], dst: &mut [u8]) {
    dst.copy_from_slice(src);
}

/// Size in bytes of the depth and item buffers of a `size × size` frame.
pub fn frame_bytes(size: u32) -> usize {
    size as usize * size as usize * (std::mem::size_of::<f32>() + std::mem::size_of::<ItemId>())
}

/// Primary rays of `camera`, one per pixel centre.
pub fn primary_rays(camera: &Pinhole) -> Vec<Ray> {
    let (w, h) = trompe::camera::Projection::resolution(camera);
    (0..h)
        .flat_map(|y| (0..w).map(move |x| (x, y)))
        .map(|(x, y)| camera.ray(trompe::frame::pixel_centre(x as f64, y as f64)))
        .collect()
}

/// Reflected rays: each primary ray that hits is mirrored about the shading normal at the hit
/// (incoherent: neighbouring rays diverge over the curved surface).
pub fn reflected_rays(bvh: &Bvh, primary: &[Ray], epsilon: f32) -> Vec<Ray> {
    primary
        .par_iter()
        .filter_map(|r| {
            let h = bvh.closest_hit(r, f32::INFINITY)?;
            Some(h.mirror_ray(r, epsilon))
        })
        .collect()
}

/// Traces every ray (closest hit, in parallel); returns how many hit.
pub fn trace_all<Q: RayQuery>(scene: &Q, rays: &[Ray]) -> usize {
    rays.par_iter()
        .filter(|r| scene.closest_hit(r, f32::INFINITY).is_some())
        .count()
}

/// One row of the `trompe bench` table.
#[derive(Clone, Debug)]
pub struct Figure {
    /// What was measured.
    pub name: String,
    /// The figure.
    pub value: f64,
    /// Its unit.
    pub unit: &'static str,
    /// A ratio against the named peer measured in the same run, if any.
    pub versus: Option<(f64, String)>,
}

/// As JSON: `{"name", "value", "unit", "versus": {"ratio", "peer"} or null}`.
impl serde::Serialize for Figure {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let versus = (self.versus.as_ref())
            .map(|(ratio, peer)| serde_json::json!({ "ratio": ratio, "peer": peer }));
        serde_json::json!({
            "name": self.name,
            "value": self.value,
            "unit": self.unit,
            "versus": versus,
        })
        .serialize(s)
    }
}

impl Figure {
    /// A duration, in milliseconds, with no peer.
    fn millis(name: impl Into<String>, t: Duration) -> Figure {
        Figure {
            name: name.into(),
            value: t.as_secs_f64() * 1e3,
            unit: "ms",
            versus: None,
        }
    }

    /// This figure with the ratio `a / b` of two durations timed in the same run, `b` being
    /// `peer`'s (which says what the ratio is: "× …" or "= … / this").
    fn versus(self, (a, b): (Duration, Duration), peer: &str) -> Figure {
        Figure {
            versus: Some((a.as_secs_f64() / b.as_secs_f64(), peer.into())),
            ..self
        }
    }
}

/// Runs the foundation benchmarks on `mesh` (the bunny); `quick` shortens every timing.
pub fn foundation(mesh: &Mesh, quick: bool) -> Result<Vec<Figure>, BenchError> {
    let min = Duration::from_millis(if quick { 200 } else { 1500 });
    let mut out = Vec::new();
    let tris = mesh.triangle_count() as f64;
    for size in [512u32, 1024] {
        let cam = framing_camera(mesh, size);
        let mut written = Ok(0);
        let t = time_median(min, || written = raster_once(&cam, mesh));
        let written = written?;
        let bytes = frame_bytes(size);
        let (src, mut dst) = (vec![1u8; bytes], vec![0u8; bytes]);
        let peer = time_median(min, || memcpy_frame(&src, &mut dst));
        out.push(Figure {
            name: format!("raster bunny {size}²: triangles"),
            value: tris / t.as_secs_f64(),
            unit: "tri/s",
            versus: None,
        });
        out.push(Figure {
            name: format!("raster bunny {size}²: pixels written"),
            value: written as f64 / t.as_secs_f64(),
            unit: "px/s",
            versus: Some((
                t.as_secs_f64() / peer.as_secs_f64(),
                format!(
                    "× the time of a memcpy of its {:.1} MB of buffers",
                    bytes as f64 / 1e6
                ),
            )),
        });
    }
    let meshes = vec![Arc::new(mesh.clone())];
    let mut bvh = None;
    let build = time_median(min, || bvh = Some(Bvh::build(meshes.clone())));
    let bvh = bvh.expect("built at least once")?;
    out.push(Figure::millis("BVH build (56k triangles)", build));
    let cam = framing_camera(mesh, 512);
    let primary = primary_rays(&cam);
    let reflected = reflected_rays(&bvh, &primary, mesh.bounds().radius() * 1e-4);
    let brute = BruteForce::new(meshes);
    for (name, rays) in [
        ("primary", &primary),
        ("reflected (incoherent)", &reflected),
    ] {
        let t = time_median(min, || {
            trace_all(&bvh, rays);
        });
        let sample: Vec<Ray> = rays
            .iter()
            .step_by((rays.len() / 256).max(1))
            .copied()
            .collect();
        let tb = time_median(min / 4, || {
            trace_all(&brute, &sample);
        });
        let bvh_rate = rays.len() as f64 / t.as_secs_f64();
        let brute_rate = sample.len() as f64 / tb.as_secs_f64();
        out.push(Figure {
            name: format!("BVH rays, {name}"),
            value: bvh_rate,
            unit: "rays/s",
            versus: Some((
                bvh_rate / brute_rate,
                "× brute force over every triangle".into(),
            )),
        });
    }
    Ok(out)
}

/// Side of the goal's SPOC impostor (a 512² SPOC impostor of the bunny).
pub const GOAL_SIZE: u32 = 512;

/// The SPOC of the goal's line and of [`impostors`]' builds: strength 0.8 around the bounding
/// sphere of `mesh`, seen from the front-right at three radii; and its eye.
pub fn goal_spoc(mesh: &Mesh) -> (Vec3, trompe::camera::Spoc) {
    let b = mesh.bounds();
    let radius = b.radius().max(1e-3);
    let eye = b.center() + Vec3::new(0.3, 0.2, 1.0).normalize() * radius * 3.0;
    let spoc = trompe::camera::Spoc::around(eye, b.center(), radius, 0.8, GOAL_SIZE)
        .expect("the eye is three radii out, outside the sphere");
    (eye, spoc)
}

/// The goal's pair alone (`trompe bench --goal`): a fresh SPOC impostor of `mesh` and its
/// strict peer, a depth + id rasterization through the SPOC's reference pinhole, timed
/// alternately for `min_time` ([`time_pair_median`]). The first line of [`impostors`] times it
/// too; alone it is quick, so that two builds of trompe can be compared by alternating many
/// short runs of each.
pub fn goal_pair(mesh: &Mesh, min_time: Duration) -> Result<(Duration, Duration), BenchError> {
    use trompe::impostor::{ImpostorCamera, albedo_of, build};
    let (_, spoc) = goal_spoc(mesh);
    let plain = spoc.pinhole().clone();
    let color = albedo_of(mesh);
    let fresh_spoc_build = || build(ImpostorCamera::Spoc(spoc.clone()), mesh, 0, &color);
    try_time_pair_median(min_time, fresh_spoc_build, || plain_raster(&plain, mesh))
}

/// Impostor workloads: building a SPOC impostor of `mesh` beside a plain pinhole
/// rasterization of it at the same resolution (depth and ids only: the strict peer of the
/// ≤ 1.5× goal) and beside its render by the raster method (the same maps a user gets from a
/// pinhole). Walks are in [`walks`].
pub fn impostors(mesh: &Mesh, quick: bool) -> Result<Vec<Figure>, BenchError> {
    use trompe::impostor::{ImpostorCamera, albedo_of, build};
    let min = Duration::from_millis(if quick { 200 } else { 1500 });
    let mut out = Vec::new();
    let b = mesh.bounds();
    let radius = b.radius().max(1e-3);
    let (eye, spoc) = goal_spoc(mesh);
    let size = GOAL_SIZE;
    let plain = spoc.pinhole().clone();
    let color = albedo_of(mesh);
    // The workload of the first three pairs below: a fresh SPOC impostor.
    let fresh_spoc_build = || build(ImpostorCamera::Spoc(spoc.clone()), mesh, 0, &color);
    // The goal's line: the very pair `trompe bench --goal` times.
    let (t_spoc, t_plain) = goal_pair(mesh, min * 2)?;
    // The same rasterization through the pinhole a pinhole impostor of the object would have:
    // framing its bounding sphere. The SPOC's reference pinhole above is wider by (1 + k)·1.05,
    // to hold the pushed-out silhouette, so the object is smaller there than in either image.
    let framed = framed_pinhole(eye, b.center(), radius, size).unwrap_or_else(|| plain.clone());
    let (t_spoc_framed, t_framed) =
        try_time_pair_median(min * 2, fresh_spoc_build, || plain_raster(&framed, mesh))?;
    // The SPOC `trompe impostor bake` places at the same eye: framed on the mesh's vertices
    // (`ImpostorCamera::fitted`), so the object fills its image — and every texel it covers
    // must be resolved — where the sphere's framing above leaves most of the image empty. And
    // the pinhole impostor `bake` would place there instead: what choosing the SPOC costs a
    // user who bakes, and what filling an impostor's maps costs when no ray is curved.
    let fitted_at_eye = |kind| {
        let (center, region) = (b.center(), radius as f64);
        ImpostorCamera::fitted(kind, eye, center, radius, region, size, &mesh.positions).ok()
    };
    let mut bake_framed = Vec::new();
    if let Some(ImpostorCamera::Spoc(fitted)) =
        fitted_at_eye(trompe::impostor::ViewCamera::Spoc(Some(0.8)))
    {
        let reference = fitted.pinhole().clone();
        let camera = ImpostorCamera::Spoc(fitted);
        let fresh = || build(camera.clone(), mesh, 0, &color);
        let (t_fitted, t_reference) =
            try_time_pair_median(min * 2, fresh, || plain_raster(&reference, mesh))?;
        let name = format!(
            "  the same build framed on the mesh, as `impostor bake` frames it ({:.1} % of \
             texels covered; {:.1} % above)",
            fresh()?.coverage() * 100.0,
            fresh_spoc_build()?.coverage() * 100.0
        );
        bake_framed.push(Figure::millis(name, t_fitted).versus(
            (t_fitted, t_reference),
            "× a depth + id rasterization through its reference pinhole (measured alternately)",
        ));
        if let Some(ImpostorCamera::Pinhole(pinhole)) =
            fitted_at_eye(trompe::impostor::ViewCamera::Pinhole)
        {
            let camera = ImpostorCamera::Pinhole(pinhole.clone());
            let fresh_pinhole = || build(camera.clone(), mesh, 0, &color);
            let (t_pinhole_imp, t_pinhole_raster) =
                try_time_pair_median(min * 2, fresh_pinhole, || plain_raster(&pinhole, mesh))?;
            let (t_spoc, t_pinhole) = try_time_pair_median(min * 2, fresh, fresh_pinhole)?;
            let name = format!(
                "  the pinhole impostor `impostor bake` frames there ({:.1} % of texels \
                 covered; {:.2} × a depth + id rasterization through its own camera)",
                fresh_pinhole()?.coverage() * 100.0,
                t_pinhole_imp.as_secs_f64() / t_pinhole_raster.as_secs_f64()
            );
            bake_framed.push(Figure::millis(name, t_pinhole).versus(
                (t_spoc, t_pinhole),
                "= the mesh-framed SPOC build time / this (same maps, measured alternately)",
            ));
        }
    }
    let (spoc_fragments, plain_fragments, framed_fragments) = (
        fragments_through(&spoc, mesh),
        fragments_through(&plain, mesh),
        fragments_through(&framed, mesh),
    );
    // The object's image rendered by the raster method (colour, distance, normals, ids).
    let render_peer = raster_view(&plain, mesh);
    let (t_spoc_again, t_render) = try_time_pair_median(min * 2, fresh_spoc_build, || {
        render_raster_once(&render_peer)
    })?;
    // What the SPOC itself costs in a fresh build: the same maps through its reference pinhole.
    let pinhole_camera = ImpostorCamera::Pinhole(plain.clone());
    let (t_spoc_vs_pinhole, t_pinhole_fresh) =
        try_time_pair_median(min * 2, fresh_spoc_build, || {
            build(pinhole_camera.clone(), mesh, 0, &color)
        })?;
    // The steady state of a dynamic scene: the same impostor rebuilt every frame, its memory
    // reused, beside a plain rasterization into a reused target.
    let mut builder = trompe::impostor::ImpostorBuilder::new();
    let mut again = build(ImpostorCamera::Spoc(spoc.clone()), mesh, 0, &color)?;
    let mut plain_target = rasterize(&plain, &[mesh], &NoAttributes, ())?.0;
    let (t_rebuild, t_plain_into) = try_time_pair_median(
        min * 2,
        || builder.rebuild(&mut again, mesh, 0, &color),
        || trompe::raster::rasterize_into(&plain, &[mesh], &NoAttributes, (), &mut plain_target),
    )?;
    // What the SPOC itself costs: the same maps through the pinhole, both rebuilt.
    let mut pinhole_builder = trompe::impostor::ImpostorBuilder::new();
    let mut pinhole_impostor = build(ImpostorCamera::Pinhole(plain.clone()), mesh, 0, &color)?;
    let (t_rebuild_again, t_pinhole) = try_time_pair_median(
        min * 2,
        || builder.rebuild(&mut again, mesh, 0, &color),
        || pinhole_builder.rebuild(&mut pinhole_impostor, mesh, 0, &color),
    )?;
    out.push(
        Figure::millis(
            format!(
                "build SPOC impostor {size}², {} triangles",
                mesh.triangle_count()
            ),
            t_spoc,
        )
        .versus(
            (t_spoc, t_plain),
            "× a plain pinhole rasterization (depth + ids; goal ≤ 1.5)",
        ),
    );
    let beside_framed = format!(
        "  the same build beside a pinhole framing the bounding sphere ({framed_fragments} \
         fragments; SPOC {spoc_fragments}, its reference pinhole {plain_fragments})"
    );
    out.push(Figure::millis(beside_framed, t_spoc_framed).versus(
        (t_spoc_framed, t_framed),
        "× a depth + id rasterization through that pinhole (measured alternately)",
    ));
    out.extend(bake_framed);
    out.push(
        Figure::millis(
            format!("build pinhole impostor {size}² (same maps, the SPOC's reference pinhole)"),
            t_pinhole_fresh,
        )
        .versus(
            (t_spoc_vs_pinhole, t_pinhole_fresh),
            "= fresh SPOC build time / this (measured alternately)",
        ),
    );
    out.push(
        Figure::millis(
            format!("render the same mesh {size}² by the raster method"),
            t_render,
        )
        .versus(
            (t_spoc_again, t_render),
            "= fresh SPOC build time / this (colour, distance, normals, ids; measured alternately)",
        ),
    );
    out.push(
        Figure::millis(
            format!("rebuild SPOC impostor {size}², memory reused"),
            t_rebuild,
        )
        .versus(
            (t_rebuild, t_plain_into),
            "× a plain rasterization into a reused target (goal ≤ 1.5)",
        ),
    );
    // Built on the first walk, not by `build`: timed apart.
    let t_pyramid = time_median(min, || {
        again.maps_changed();
        std::hint::black_box(again.pyramid());
    });
    out.push(Figure::millis(
        "walk index of that impostor (front-bound pyramid, packed texel planes; first walk)",
        t_pyramid,
    ));
    out.push(
        Figure::millis(
            format!("rebuild pinhole impostor {size}² (same maps)"),
            t_pinhole,
        )
        .versus(
            (t_rebuild_again, t_pinhole),
            "= SPOC rebuild time / this (measured alternately)",
        ),
    );
    Ok(out)
}

/// `mesh` with every material's texture left out (its base colours kept): the peer that prices
/// texture sampling.
pub fn without_textures(mesh: &Mesh) -> Mesh {
    Mesh {
        materials: (mesh.materials.iter())
            .map(|m| trompe::geom::Material {
                texture: None,
                ..m.clone()
            })
            .collect(),
        ..mesh.clone()
    }
}

/// A textured mesh's SPOC impostor (the maps of what a technical artist bakes): a fresh
/// [`GOAL_SIZE`]² build of `mesh` framed as the goal's ([`goal_spoc`]), its colour sampled from
/// its textures texel by texel, beside a depth + id rasterization through the SPOC's reference
/// pinhole (the goal's peer) and beside the same build with its textures left out — what
/// sampling them costs, where an untextured mesh's colour repeats from texel to texel.
/// `name` labels the mesh. Nothing when `mesh` has no texture.
pub fn textured_impostor(mesh: &Mesh, name: &str, quick: bool) -> Result<Vec<Figure>, BenchError> {
    use trompe::impostor::{ImpostorCamera, albedo_of, build};
    if mesh.materials.iter().all(|m| m.texture.is_none()) {
        return Ok(Vec::new());
    }
    let min = Duration::from_millis(if quick { 200 } else { 1500 });
    let (_, spoc) = goal_spoc(mesh);
    let plain = spoc.pinhole().clone();
    let untextured = without_textures(mesh);
    let (sampled, flat) = (albedo_of(mesh), albedo_of(&untextured));
    let camera = ImpostorCamera::Spoc(spoc);
    let textured_build = || build(camera.clone(), mesh, 0, &sampled);
    let flat_build = || build(camera.clone(), &untextured, 0, &flat);
    let (t_textured, t_plain) =
        try_time_pair_median(min * 2, textured_build, || plain_raster(&plain, mesh))?;
    let (t_textured_again, t_flat) = try_time_pair_median(min * 2, textured_build, flat_build)?;
    let size = GOAL_SIZE;
    let coverage = textured_build()?.coverage();
    Ok(vec![
        Figure::millis(
            format!(
                "build SPOC impostor {size}² of a textured mesh ({name}, {} triangles; {:.1} % \
                 of texels covered)",
                mesh.triangle_count(),
                coverage * 100.0
            ),
            t_textured,
        )
        .versus(
            (t_textured, t_plain),
            "× a depth + id rasterization through its reference pinhole (measured alternately)",
        ),
        Figure::millis("  the same build with its textures left out", t_flat).versus(
            (t_textured_again, t_flat),
            "= the textured build time / this (measured alternately)",
        ),
    ])
}

/// Graph-camera impostor construction (paper 1 §4.5; the paper builds its maze with 4 bunnies,
/// 66 k triangles, at over 100 frames a second on a GPU): the demo maze with four copies of
/// `object`, `size²`, beside a depth + id rasterization of the same triangles through the
/// camera's root pinhole (what a pinhole impostor from the entrance costs).
pub fn graph_impostors(
    maze: &trompe::scene::maze::Maze,
    maze_path: &std::path::Path,
    object: &Mesh,
    quick: bool,
) -> Result<Vec<Figure>, BenchError> {
    use trompe::impostor::{ImpostorCamera, albedo_of, build};
    let min = Duration::from_millis(if quick { 200 } else { 1500 });
    let size = 512;
    let g = maze.graph_camera(size, maze_path)?;
    let mesh = trompe::scene::maze::Maze::with_objects(maze, object, 4);
    let color = albedo_of(&mesh);
    let camera = ImpostorCamera::Graph(g.clone());
    let (t_graph, t_root) = try_time_pair_median(
        min * 2,
        || build(camera.clone(), &mesh, 0, &color),
        || plain_raster(g.root(), &mesh),
    )?;
    // Rebuilt every frame, its memory reused, beside the root rasterization into a reused target.
    let mut builder = trompe::impostor::ImpostorBuilder::new();
    let mut again = build(camera.clone(), &mesh, 0, &color)?;
    let mut root_target = rasterize(g.root(), &[&mesh], &NoAttributes, ())?.0;
    let (t_rebuild, t_root_into) = try_time_pair_median(
        min * 2,
        || builder.rebuild(&mut again, &mesh, 0, &color),
        || trompe::raster::rasterize_into(g.root(), &[&mesh], &NoAttributes, (), &mut root_target),
    )?;
    let built = format!(
        "build graph-camera impostor {size}², maze + 4 bunnies ({} triangles, {} frusta)",
        mesh.triangle_count(),
        g.frusta().len()
    );
    let rebuilt = format!("rebuild graph-camera impostor {size}², memory reused");
    Ok(vec![
        Figure::millis(built, t_graph).versus(
            (t_graph, t_root),
            "× a depth + id rasterization of the same triangles through its root pinhole \
             (measured alternately)",
        ),
        Figure::millis(rebuilt, t_rebuild).versus(
            (t_rebuild, t_root_into),
            "× that rasterization into a reused target (measured alternately)",
        ),
    ])
}

/// What `trompe bench` measured: a heading and its rows (as JSON, the same).
#[derive(serde::Serialize)]
pub struct BenchReport {
    /// The mesh and thread count.
    pub heading: String,
    /// The rows.
    pub figures: Vec<Figure>,
}

impl std::fmt::Display for BenchReport {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}", self.heading)?;
        for fig in &self.figures {
            let versus = fig
                .versus
                .as_ref()
                .map_or(String::new(), |(r, peer)| format!("   ({r:.2} {peer})"));
            write!(
                f,
                "\n  {:<48} {:>12.4} {:<7}{versus}",
                fig.name, fig.value, fig.unit
            )?;
        }
        Ok(())
    }
}

/// Why `trompe bench` could not run: a shipped input did not load.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum BenchError {
    /// A mesh did not load.
    #[error(transparent)]
    Mesh(#[from] trompe::geom::MeshError),
    /// The maze did not load.
    #[error(transparent)]
    Maze(#[from] trompe::scene::maze::MazeError),
    /// A shipped scene did not load.
    #[error(transparent)]
    Scene(#[from] Box<trompe::scene::SceneError>),
    /// A camera of a shipped scene is invalid.
    #[error(transparent)]
    Camera(#[from] trompe::camera::CameraError),
    /// A shipped scene could not be placed at its time.
    #[error(transparent)]
    View(#[from] trompe::scene::ViewError),
    /// A relief workload failed.
    #[error(transparent)]
    Relief(#[from] trompe::relief::ReliefError),
    /// A Master Texture workload failed.
    #[error(transparent)]
    Master(#[from] trompe::master::MasterError),
    /// A layers workload failed.
    #[error(transparent)]
    Layers(#[from] Box<trompe::layers::LayersError>),
    /// A render failed.
    #[error(transparent)]
    Render(#[from] trompe::render::RenderError),
    /// An octahedral bake failed.
    #[error(transparent)]
    Octahedral(#[from] trompe::octahedral::BakeError),
    /// An image could not be made.
    #[error(transparent)]
    Frame(#[from] trompe::frame::FrameError),
    /// A method of the registry failed.
    #[error(transparent)]
    Method(#[from] trompe::methods::MethodError),
    /// The GPU could not be opened or failed.
    #[error(transparent)]
    Gpu(#[from] trompe_gpu::GpuError),
    /// An impostor built on the GPU.
    #[error(transparent)]
    GpuBuild(#[from] trompe_gpu::build::BuildError),
    /// A method failed on one of its devices.
    #[error(transparent)]
    Device(#[from] trompe_gpu::DeviceError),
    /// An impostor's depth layers could not be peeled.
    #[error(transparent)]
    Peel(#[from] trompe::impostor::LayerError),
    /// What a workload holds (a BVH) would pass the memory budget.
    #[error(transparent)]
    Memory(#[from] trompe::memory::OverBudget),
    /// A thread pool could not be made.
    #[error("a benchmark's thread pool could not be started")]
    Threads,
}

/// The heading of a bench run on `mesh`, read from `path`.
pub fn heading(path: &std::path::Path, mesh: &Mesh) -> String {
    format!(
        "trompe bench on {} ({} triangles), {} threads",
        path.display(),
        mesh.triangle_count(),
        rayon::current_num_threads()
    )
}

/// Every `trompe bench` workload: the foundation's on `mesh` (read from `path`), then the
/// impostors' on the shipped teapot, bunny, Duck and maze found under `inputs`.
pub fn run(
    path: &std::path::Path,
    mesh: &Mesh,
    inputs: &trompe::eval::fixtures::Shipped,
    quick: bool,
) -> Result<BenchReport, BenchError> {
    let assets = &inputs.assets;
    let bunny = trompe::geom::io::load(&assets.join("meshes/bunny.obj"))?.mesh;
    let maze_path = inputs.scenes.join("maze.maze");
    let maze = trompe::scene::maze::Maze::load(&maze_path)?;
    let duck = trompe::geom::io::load(&assets.join("gltf/Duck.glb"))?.mesh;
    let figures = foundation(mesh, quick)?
        .into_iter()
        .chain(impostors(mesh, quick)?)
        .chain(walks::walks(inputs, quick)?)
        .chain(textured_impostor(&duck, "Duck.glb", quick)?)
        .chain(graph_impostors(&maze, &maze_path, &bunny, quick)?)
        .chain(relief::relief(inputs, quick)?)
        .chain(master::master(inputs, quick)?)
        .chain(layers::layers(inputs, quick)?)
        .collect();
    Ok(BenchReport {
        heading: heading(path, mesh),
        figures,
    })
}

/// `trompe bench --goal RUNS`: the goal's pair alone ([`goal_pair`]), `runs` times, 3 s each.
pub struct GoalReport {
    /// The bench heading.
    pub heading: String,
    /// Per run: the build's and the peer's median durations.
    pub runs: Vec<(Duration, Duration)>,
}

/// Times [`goal_pair`] on `mesh` (read from `path`) `runs` times.
pub fn goal(path: &std::path::Path, mesh: &Mesh, runs: u32) -> Result<GoalReport, BenchError> {
    Ok(GoalReport {
        heading: heading(path, mesh),
        runs: (0..runs)
            .map(|_| goal_pair(mesh, Duration::from_secs(3)))
            .collect::<Result<_, _>>()?,
    })
}

/// As JSON: the heading and each run's build and peer milliseconds and their ratio.
impl serde::Serialize for GoalReport {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let runs: Vec<_> = (self.runs.iter())
            .map(|(build, peer)| {
                serde_json::json!({
                    "build_ms": build.as_secs_f64() * 1e3,
                    "peer_ms": peer.as_secs_f64() * 1e3,
                    "ratio": build.as_secs_f64() / peer.as_secs_f64(),
                })
            })
            .collect();
        serde_json::json!({ "heading": self.heading, "runs": runs }).serialize(s)
    }
}

impl std::fmt::Display for GoalReport {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        writeln!(f, "{}", self.heading)?;
        write!(
            f,
            "fresh SPOC impostor {GOAL_SIZE}² / depth + id rasterization through its reference pinhole (goal ≤ 1.5)"
        )?;
        let mut ratios = Vec::new();
        for (run, (build, peer)) in self.runs.iter().enumerate() {
            let ratio = build.as_secs_f64() / peer.as_secs_f64();
            write!(
                f,
                "\n  run {}: build {:.3} ms, peer {:.3} ms, {ratio:.3} ×",
                run + 1,
                build.as_secs_f64() * 1e3,
                peer.as_secs_f64() * 1e3
            )?;
            ratios.push(ratio);
        }
        ratios.sort_by(f64::total_cmp);
        if let (Some(lo), Some(hi)) = (ratios.first(), ratios.last()) {
            let median = trompe::eval::fidelity::median(&ratios);
            write!(
                f,
                "\n{} runs: {lo:.3} – {hi:.3} ×, median {median:.3} ×",
                ratios.len()
            )?;
        }
        Ok(())
    }
}
