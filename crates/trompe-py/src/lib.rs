//! trompe for Python: the native half of the `trompe` package (`python/trompe/` is the other,
//! which turns what this returns into dicts and NumPy arrays). Each function loads, calls the
//! library as the command line does — outputs that are inputs refused first — and returns a
//! report as JSON text (the documents of `--json`, `docs/json.md`) or an image as raw bytes
//! with its size.
//!
//! Invariant: a library error is raised as `trompe.TrompeError` with the message the command
//! line prints (the error and its causes, each said once); nothing panics on user input.

use pyo3::exceptions::PyException;
use pyo3::prelude::*;
use std::path::{Path, PathBuf};
use trompe::files::OutputPlan;
use trompe::impostor::{CameraChoice, Layers, Subject, ViewCamera};

pyo3::create_exception!(
    _native,
    TrompeError,
    PyException,
    "An error from trompe: the message names the file, the element and the reason."
);

/// `e` and its causes joined by ": ", each said once (as the command line prints them).
fn error(e: &(dyn std::error::Error + 'static)) -> PyErr {
    let mut message = String::new();
    let mut cause = Some(e);
    while let Some(c) = cause {
        let text = c.to_string();
        if !message.contains(&text) {
            if !message.is_empty() {
                message.push_str(": ");
            }
            message.push_str(&text);
        }
        cause = c.source();
    }
    TrompeError::new_err(message)
}

// The functions take the Python wrapper's keyword arguments one by one (`python/trompe/`
// names and documents them): hence `too_many_arguments` allowed on a few.

/// A library result as a Python one.
trait OrRaise<T> {
    fn or_raise(self) -> PyResult<T>;
}

impl<T, E: std::error::Error + 'static> OrRaise<T> for Result<T, E> {
    fn or_raise(self) -> PyResult<T> {
        self.map_err(|e| error(&e))
    }
}

/// A refusal of an argument, by name.
fn invalid(what: &str, reason: impl std::fmt::Display) -> PyErr {
    TrompeError::new_err(format!("{what}: {reason}"))
}

fn json(value: &impl serde::Serialize) -> PyResult<String> {
    serde_json::to_string(value).map_err(|e| invalid("the report", e))
}

/// Floats as little-endian bytes, for `numpy.frombuffer`.
fn f32_bytes(values: impl Iterator<Item = f32>) -> Vec<u8> {
    values.flat_map(f32::to_le_bytes).collect()
}

/// A mesh file's summary (what `trompe info` prints), its positions (`3n` floats) and its
/// triangles (`3m` vertex indices), as JSON text and little-endian bytes.
#[pyfunction]
fn load_mesh(path: PathBuf) -> PyResult<(String, Vec<u8>, Vec<u8>)> {
    let loaded = trompe::geom::io::load(&path).or_raise()?;
    let summary = json(&loaded.summary(&path))?;
    let m = &loaded.mesh;
    let positions = f32_bytes(m.positions.iter().flat_map(|p| p.to_array()));
    let triangles = m
        .triangles
        .iter()
        .flat_map(|t| t.iter().flat_map(|i| i.to_le_bytes()))
        .collect();
    Ok((summary, positions, triangles))
}

/// The summary of an impostor's or an atlas's JSON sidecar (what `trompe info` prints).
#[pyfunction]
fn sidecar_info(path: PathBuf) -> PyResult<String> {
    use trompe::sidecar::SidecarKind;
    match SidecarKind::of(&path).or_raise()? {
        SidecarKind::Impostor => {
            let imp = trompe::impostor::file::load(&path).or_raise()?;
            json(&imp.summary(&path))
        }
        SidecarKind::Octahedral => {
            let sidecar = trompe::octahedral::file::read_sidecar(&path).or_raise()?;
            let mut v = serde_json::json!(sidecar);
            v["kind"] = "octahedral".into();
            v["path"] = serde_json::json!(path);
            json(&v)
        }
    }
}

/// The camera named `camera` (with SPOC strength `k`).
fn camera_choice(camera: &str, k: Option<f64>) -> PyResult<CameraChoice> {
    if let Some(k) = k.filter(|k| !(k.is_finite() && *k >= 0.0)) {
        return Err(invalid("k", format!("{k} must be a finite number ≥ 0")));
    }
    Ok(match camera {
        "spoc" => CameraChoice::Placed(ViewCamera::Spoc(k)),
        "pinhole" => CameraChoice::Placed(ViewCamera::Pinhole),
        "orthographic" => CameraChoice::Placed(ViewCamera::Orthographic),
        "graph" => CameraChoice::Graph,
        other => {
            return Err(invalid(
                "camera",
                format!("{other:?} (spoc, pinhole, orthographic or graph)"),
            ));
        }
    })
}

fn layers(text: &str) -> PyResult<Layers> {
    text.parse().map_err(|e| invalid("layers", e))
}

/// Loads a mesh or a maze, checking `plan` (the outputs it writes) against what it reads.
fn subject(path: &Path, plan: &mut OutputPlan) -> PyResult<Subject> {
    let (subject, _warnings) = Subject::load(path).or_raise()?;
    plan.reads([path]).reads(subject.files());
    plan.check().or_raise()?;
    Ok(subject)
}

/// Bakes a depth-image impostor of `input` to the sidecar `output` (its EXR and preview beside
/// it), as `trompe impostor bake` does; the report as JSON text.
#[pyfunction]
#[pyo3(signature = (input, output, camera, resolution, from_dir, distance, k, layers_text))]
#[allow(clippy::too_many_arguments)]
fn bake_impostor(
    input: PathBuf,
    output: PathBuf,
    camera: &str,
    resolution: u32,
    from_dir: [f32; 3],
    distance: f32,
    k: Option<f64>,
    layers_text: &str,
) -> PyResult<String> {
    if !(1..=8192).contains(&resolution) {
        return Err(invalid("resolution", format!("{resolution} is not 1–8192")));
    }
    let settings = trompe::impostor::BakeSettings {
        camera: camera_choice(camera, k)?,
        resolution,
        from: glam::Vec3::from_array(from_dir),
        distance,
        layers: layers(layers_text)?,
    };
    let mut plan = OutputPlan::new();
    plan.creating_folders()
        .writes(&output, &["json"])
        .writes(output.with_extension("exr"), &["exr"])
        .writes(output.with_extension("png"), &["png"]);
    plan.check_overwrites().or_raise()?;
    let subject = subject(&input, &mut plan)?;
    plan.make_folders().or_raise()?;
    let report = trompe::impostor::bake(&subject, &settings, &output).or_raise()?;
    json(&report)
}

/// Bakes octahedral atlases of every mesh in `inputs` (files and folders) into the folder
/// `output`, as `trompe impostor bake --octahedral` bakes a batch; `progress(done, total,
/// input)` is called after each. The manifest as JSON text.
#[pyfunction]
#[pyo3(signature = (inputs, output, frames, resolution, glb, exr, skip_existing, progress))]
#[allow(clippy::too_many_arguments)]
fn bake_octahedral(
    py: Python<'_>,
    inputs: Vec<PathBuf>,
    output: PathBuf,
    frames: u32,
    resolution: u32,
    glb: bool,
    exr: bool,
    skip_existing: bool,
    progress: Option<Py<PyAny>>,
) -> PyResult<String> {
    use trompe::octahedral::batch::{BatchSettings, Shard, bake_all, gather};
    use trompe::octahedral::{BakeSettings, Coverage, Grid};
    if !(2..=64).contains(&frames) {
        return Err(invalid("frames", format!("{frames} is not 2–64")));
    }
    let frame_size = resolution / frames;
    if frame_size < 8 {
        return Err(invalid(
            "resolution",
            format!(
                "{resolution} / {frames} frames leaves {frame_size} texels a frame; give at least 8"
            ),
        ));
    }
    let grid = Grid {
        n: frames,
        coverage: Coverage::Sphere,
    };
    let settings = BatchSettings {
        bake: BakeSettings::new(grid, frame_size),
        glb: glb.then_some(trompe::octahedral::gltf::TextureFormat::Png),
        floats: match exr {
            true => trompe::octahedral::file::FloatMaps::OpenExr,
            false => trompe::octahedral::file::FloatMaps::Omitted,
        },
        skip_existing,
    };
    let batch = gather(&inputs, &[]).or_raise()?;
    let total = batch.len();
    let mut plan = OutputPlan::new();
    plan.reads(batch.iter().map(|i| i.path.clone()));
    for input in &batch {
        let sidecar = input.sidecar(&output);
        for file in trompe::octahedral::file::files(&sidecar) {
            plan.writes(file, &["json", "png", "exr"]);
        }
        if glb {
            plan.writes(sidecar.with_extension("glb"), &["glb"]);
        }
    }
    plan.check_overwrites().or_raise()?;
    // A file of the user's where a map would go (not an earlier atlas's) is never replaced.
    for input in &batch {
        trompe::octahedral::file::check_replaceable(&input.sidecar(&output), settings.floats)
            .or_raise()?;
    }
    std::fs::create_dir_all(&output).map_err(|e| invalid(&output.display().to_string(), e))?;
    let mut done = 0;
    let mut failure = None;
    let shard = Shard { index: 1, count: 1 };
    let manifest = bake_all(&batch, &output, settings, shard, &mut |entry, _| {
        done += 1;
        if let (Some(callback), None) = (&progress, &failure) {
            let input = entry.input.display().to_string();
            if let Err(e) = callback.call1(py, (done, total, input)) {
                failure = Some(e);
            }
        }
    })
    .or_raise()?;
    match failure {
        Some(e) => Err(e),
        None => json(&manifest),
    }
}

/// Checks an impostor against the exact BVH, as `trompe impostor check` does: one built
/// through `camera` (`impostor` absent), or the baked `impostor`; the report as JSON text.
#[pyfunction]
#[pyo3(signature = (mesh, impostor, camera, resolution, k, rays, region, layers_text))]
#[allow(clippy::too_many_arguments)]
fn check_impostor(
    mesh: PathBuf,
    impostor: Option<PathBuf>,
    camera: &str,
    resolution: u32,
    k: Option<f64>,
    rays: u32,
    region: f32,
    layers_text: &str,
) -> PyResult<String> {
    use trompe::eval::check::{BakedCheckSettings, CheckSettings, check_baked, check_built};
    let mut plan = OutputPlan::new();
    if let Some(sidecar) = &impostor {
        plan.reads([sidecar.clone(), sidecar.with_extension("exr")]);
    }
    let subject = subject(&mesh, &mut plan)?;
    let report = match impostor {
        None => {
            if !(1..=8192).contains(&resolution) {
                return Err(invalid("resolution", format!("{resolution} is not 1–8192")));
            }
            let settings = CheckSettings {
                camera: camera_choice(camera, k)?,
                resolution,
                reflector: None,
                distance: 1.4,
                view: 1024,
                sphere_rays: 0,
                layers: layers(layers_text)?,
                misses: false,
            };
            check_built(&subject, &settings).or_raise()?
        }
        Some(path) => {
            if !(1..=10_000_000).contains(&rays) {
                return Err(invalid("rays", format!("{rays} is not 1–10 000 000")));
            }
            let baked = trompe::impostor::file::load(&path).or_raise()?;
            let settings = BakedCheckSettings {
                reflector: None,
                view: 1024,
                region,
                rays,
                misses: false,
            };
            check_baked(&subject, baked, &path, &settings).or_raise()?
        }
    };
    json(&report)
}

/// Renders calibrated views of `mesh` into the folder `output` (PNGs and a COLMAP text model),
/// as `trompe views capture` does; what was written as JSON text.
#[pyfunction]
#[pyo3(signature = (mesh, output, count, size, rig))]
fn capture_views(
    mesh: PathBuf,
    output: PathBuf,
    count: u32,
    size: (u32, u32),
    rig: &str,
) -> PyResult<String> {
    use trompe::files::FolderKind;
    use trompe::views::capture::{CaptureSettings, Rig, capture, write_capture};
    let rig = match rig {
        "ring" => Rig::Ring,
        "sphere" => Rig::Sphere,
        "hemisphere" => Rig::Hemisphere,
        other => {
            return Err(invalid(
                "rig",
                format!("{other:?} (ring, sphere or hemisphere)"),
            ));
        }
    };
    let mut plan = OutputPlan::new();
    plan.reads([&mesh])
        .writes_folder(&output, FolderKind::Capture)
        .writes(output.join("cameras.txt"), &["txt"])
        .creating_folders();
    plan.check().or_raise()?;
    let settings = CaptureSettings {
        rig,
        count: count as usize,
        size,
        ..CaptureSettings::default()
    };
    let set = capture(&mesh, &settings, &()).or_raise()?;
    write_capture(&output, &set).or_raise()?;
    json(&serde_json::json!({
        "views": set.views.len(),
        "size": [size.0, size.1],
        "folder": output,
    }))
}

/// The weighting named `name`.
fn weighting(name: &str) -> PyResult<trompe::views::Weighting> {
    use trompe::views::Weighting;
    Ok(match name {
        "ulr" => Weighting::Ulr { beta: 0.1 },
        "vdtm" => Weighting::Vdtm,
        "view-map" => Weighting::ViewMap,
        "best-face" => Weighting::BestFace,
        other => {
            return Err(invalid(
                "weights",
                format!("{other:?} (ulr, vdtm, view-map or best-face)"),
            ));
        }
    })
}

/// Leaves every `every`-th view of a COLMAP model out and renders it from the others, as
/// `trompe views score` does; the scores as JSON text.
#[pyfunction]
#[pyo3(signature = (model, mesh, weights, every, k))]
fn score_views(
    model: PathBuf,
    mesh: PathBuf,
    weights: Vec<String>,
    every: Option<usize>,
    k: usize,
) -> PyResult<String> {
    let mut set = trompe::views::ViewSet::load(&model, None).or_raise()?;
    set.load_images().or_raise()?;
    let mesh = trompe::geom::io::load(&mesh).or_raise()?.mesh;
    let weightings = weights
        .iter()
        .map(|w| weighting(w))
        .collect::<PyResult<Vec<_>>>()?;
    let n = set.views.len();
    let every = every.unwrap_or((n / 12).max(1)).max(1);
    let which: Vec<usize> = (0..n).step_by(every).collect();
    if !(1..=64).contains(&k) {
        return Err(invalid("k", format!("{k} is not 1–64")));
    }
    let settings = trompe::views::BlendSettings {
        k,
        ..Default::default()
    };
    let reports =
        trompe::views::score::leave_one_out(&set, &mesh, &settings, &weightings, &which, &())
            .or_raise()?;
    json(&serde_json::json!({
        "views": n,
        "left_out": which.len(),
        "weightings": reports,
    }))
}

/// A frame: width, height, colour (`4wh` floats, linear RGBA), object ids (`wh` u32s,
/// 0xffffffff where nothing is seen), depth (`wh` floats), and the method's report.
type FrameBytes = (u32, u32, Vec<u8>, Vec<u8>, Vec<u8>, String);

fn frame_bytes(frame: &trompe::frame::Frame, report: String) -> FrameBytes {
    let (w, h) = frame.color.size();
    (
        w,
        h,
        f32_bytes(frame.color.pixels().iter().flat_map(|c| c.to_array())),
        frame
            .object_id
            .pixels()
            .iter()
            .flat_map(|i| i.to_le_bytes())
            .collect(),
        f32_bytes(frame.depth.pixels().iter().copied()),
        report,
    )
}

/// Renders the scene file `scene` at time `time` (its own by default) by `method` (any the
/// library lists, `trompe render --help`), at `size` if given.
#[pyfunction]
#[pyo3(signature = (scene, method, time, size))]
fn render(
    scene: PathBuf,
    method: &str,
    time: Option<f32>,
    size: Option<(u32, u32)>,
) -> PyResult<FrameBytes> {
    use trompe::methods::{MethodKind, MethodSettings, Renderer};
    let kind: MethodKind = method.parse().or_raise()?;
    let mut scene = trompe::scene::Scene::load(&scene).or_raise()?;
    if let Some((w, h)) = size {
        let (w, h) = trompe::frame::check_size(u64::from(w), u64::from(h)).or_raise()?;
        scene.camera.width = w;
        scene.camera.height = h;
    }
    let t = time.unwrap_or(scene.render.time);
    let mut renderer = Renderer::new(&scene, kind, MethodSettings::default()).or_raise()?;
    let out = renderer.frame(t, None, &()).or_raise()?;
    Ok(frame_bytes(&out.frame, out.report))
}

/// Renders `mesh` from the camera of the scene file `scene`, textured from a COLMAP model's
/// views, as `trompe views render` does: width, height and linear RGBA floats (alpha 0 where
/// no view sees it).
#[pyfunction]
#[pyo3(signature = (model, mesh, scene, weights, k))]
fn render_views(
    model: PathBuf,
    mesh: PathBuf,
    scene: PathBuf,
    weights: &str,
    k: usize,
) -> PyResult<(u32, u32, Vec<u8>)> {
    let mut set = trompe::views::ViewSet::load(&model, None).or_raise()?;
    set.load_images().or_raise()?;
    let mesh = trompe::geom::io::load(&mesh).or_raise()?.mesh;
    let scene = trompe::scene::Scene::load(&scene).or_raise()?;
    let camera = scene.view(scene.render.time).or_raise()?.camera;
    let depth = trompe::views::visibility::DepthMap::of_all(&set.views, &mesh).or_raise()?;
    if !(1..=64).contains(&k) {
        return Err(invalid("k", format!("{k} is not 1–64")));
    }
    let settings = trompe::views::BlendSettings {
        k,
        weighting: weighting(weights)?,
        ..Default::default()
    };
    let b = trompe::views::blend::render(&camera, &mesh, &set.views, &depth, &settings, None)
        .or_raise()?;
    let (w, h) = b.image.size();
    Ok((
        w,
        h,
        f32_bytes(b.image.pixels().iter().flat_map(|c| c.to_array())),
    ))
}

/// An image file (PNG, EXR, HDR) as width, height and linear RGBA floats.
#[pyfunction]
fn read_image(path: PathBuf) -> PyResult<(u32, u32, Vec<u8>)> {
    let image = trompe::frame::io::read_color(&path).or_raise()?;
    let (w, h) = image.size();
    Ok((
        w,
        h,
        f32_bytes(image.pixels().iter().flat_map(|c| c.to_array())),
    ))
}

/// PSNR, SSIM and FLIP of two image files, as `trompe compare` prints them, as JSON text.
#[pyfunction]
fn compare(reference: PathBuf, test: PathBuf) -> PyResult<String> {
    use trompe::frame::{io, metrics};
    metrics::budget_compare(&[&reference, &test]).or_raise()?;
    let a = io::read_color(&reference).or_raise()?;
    let b = io::read_color(&test).or_raise()?;
    let s = metrics::compare(&a, &b, None).or_raise()?;
    json(&serde_json::json!({ "psnr_db": s.psnr, "ssim": s.ssim, "flip": s.flip }))
}

/// The library's methods that render scenes, by name.
#[pyfunction]
fn methods() -> Vec<&'static str> {
    trompe::methods::MethodKind::ALL
        .into_iter()
        .filter(|k| k.refusal().is_none())
        .map(|k| k.name())
        .collect()
}

/// The native module.
#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("TrompeError", m.py().get_type::<TrompeError>())?;
    m.add("VERSION", env!("CARGO_PKG_VERSION"))?;
    m.add_function(wrap_pyfunction!(load_mesh, m)?)?;
    m.add_function(wrap_pyfunction!(sidecar_info, m)?)?;
    m.add_function(wrap_pyfunction!(bake_impostor, m)?)?;
    m.add_function(wrap_pyfunction!(bake_octahedral, m)?)?;
    m.add_function(wrap_pyfunction!(check_impostor, m)?)?;
    m.add_function(wrap_pyfunction!(capture_views, m)?)?;
    m.add_function(wrap_pyfunction!(score_views, m)?)?;
    m.add_function(wrap_pyfunction!(render, m)?)?;
    m.add_function(wrap_pyfunction!(render_views, m)?)?;
    m.add_function(wrap_pyfunction!(read_image, m)?)?;
    m.add_function(wrap_pyfunction!(compare, m)?)?;
    m.add_function(wrap_pyfunction!(methods, m)?)?;
    Ok(())
}
