//! The demo report: `trompe demo` renders the scenes shipped in `scenes/`, measures every method
//! against the exact one, and writes `index.html` — run metadata, a table of contents, then one
//! `html::Section` per capability (`foundation`, `impostors`, `maze`, `views`, `photographs`, `layers`, `relief`, `master`), each built as data and
//! written by the one HTML writer in `html`. A new capability adds a section file and one line
//! in `demo`.

mod foundation;
pub mod html;
mod hybrid;
mod impostors;
mod layers;
mod master;
mod maze;
mod octahedral;
mod photographs;
mod relief;
mod turn;
mod views;

use html::{Report, Section, Table};
use std::path::{Path, PathBuf};
use std::time::Duration;
use thiserror::Error;
use trompe::frame::metrics::{self, Scores};
use trompe::frame::{FrameError, io};
use trompe::methods::{MethodError, MethodKind};
use trompe::render::{Progress, RenderError};
use trompe::scene::SceneError;

/// Errors from building the report.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum ReportError {
    /// A shipped scene failed to load.
    #[error(transparent)]
    Scene(#[from] Box<SceneError>),
    /// Rendering failed.
    #[error(transparent)]
    Render(#[from] RenderError),
    /// A method of the registry failed.
    #[error(transparent)]
    Method(#[from] MethodError),
    /// An image could not be written or compared.
    #[error(transparent)]
    Frame(#[from] FrameError),
    /// A shipped mesh failed to load.
    #[error(transparent)]
    Mesh(#[from] trompe::geom::MeshError),
    /// A capture or a blend of calibrated views failed.
    #[error(transparent)]
    Views(#[from] trompe::views::ViewsError),
    /// A capture could not be rendered.
    #[error(transparent)]
    Capture(#[from] trompe::views::capture::CaptureError),
    /// An octahedral bake failed.
    #[error(transparent)]
    Octahedral(#[from] trompe::octahedral::BakeError),
    /// A scene could not be drawn from octahedral atlases.
    #[error(transparent)]
    OctahedralScene(#[from] trompe::octahedral::scene::SceneAtlasError),
    /// A relief walk failed.
    #[error(transparent)]
    Relief(Box<trompe::relief::ReliefError>),
    /// A Master Texture encoding failed.
    #[error(transparent)]
    Master(Box<trompe::master::MasterError>),
    /// Layered projective textures failed.
    #[error(transparent)]
    Layers(Box<trompe::layers::LayersError>),
    /// A camera of a shipped scene is invalid.
    #[error(transparent)]
    Camera(#[from] trompe::camera::CameraError),
    /// A shipped scene could not be placed at its time.
    #[error(transparent)]
    View(#[from] trompe::scene::ViewError),
    /// A timed workload failed.
    #[error(transparent)]
    Bench(Box<crate::bench::BenchError>),
    /// The output directory is a user's, or another command's result.
    #[error(transparent)]
    Folder(#[from] trompe::files::FolderError),
    /// What a section holds (a BVH) would pass the memory budget.
    #[error(transparent)]
    Memory(#[from] trompe::memory::OverBudget),
    /// The output directory could not be written.
    #[error("{path}: {source}")]
    Io {
        /// The file or directory.
        path: PathBuf,
        /// The cause.
        source: std::io::Error,
    },
}

pub use trompe::eval::fixtures::Shipped as DemoInputs;

/// One rendered scene/method pair.
#[derive(Clone, Debug)]
pub struct RenderRow {
    /// Scene name.
    pub scene: String,
    /// Method.
    pub method: MethodKind,
    /// Wall-clock time of the render.
    pub time: Duration,
    /// Scores against the trace render of the same scene.
    pub scores: Scores,
    /// Fraction of pixels with the same object id as the trace render.
    pub id_agreement: f64,
}

/// What the demo measured (also printed by the CLI).
#[derive(Clone, Debug, Default)]
pub struct DemoSummary {
    /// Renders.
    pub renders: Vec<RenderRow>,
    /// The report file.
    pub index: PathBuf,
}

fn io_err(path: &Path) -> impl FnOnce(std::io::Error) -> ReportError + '_ {
    move |source| ReportError::Io {
        path: path.to_path_buf(),
        source,
    }
}

/// Writes the demo report into `out`; `progress(label, rows)` gives a progress sink per render.
pub fn demo(
    inputs: &DemoInputs,
    out: &Path,
    progress: &dyn Fn(&str, u64) -> Box<dyn Progress>,
) -> Result<DemoSummary, ReportError> {
    claim_directory(out)?;
    let started = std::time::Instant::now();
    let mut report = Report {
        title: "trompe — demo report".into(),
        metadata: metadata(inputs),
        sections: Vec::new(),
    };
    let mut summary = DemoSummary::default();
    let mut steps = Table::new(["section", "time"]);
    let mut timed = |name: &str, t: std::time::Instant| {
        steps.row([
            name.to_string(),
            format!("{:.1} s", t.elapsed().as_secs_f64()),
        ]);
    };
    let t = std::time::Instant::now();
    let (renderers, rows) = foundation::section(inputs, out, progress)?;
    timed("ground-truth renderers", t);
    summary.renders = rows;
    report.sections.push(renderers);
    let t = std::time::Instant::now();
    report.sections.push(impostors::section(inputs, out)?);
    timed("non-pinhole impostors", t);
    let t = std::time::Instant::now();
    report.sections.push(maze::section(inputs, out)?);
    timed("graph camera", t);
    let t = std::time::Instant::now();
    report.sections.push(hybrid::section(inputs, out)?);
    timed("hybrid reflections", t);
    let t = std::time::Instant::now();
    report.sections.push(octahedral::section(inputs, out)?);
    timed("octahedral impostors", t);
    let t = std::time::Instant::now();
    report.sections.push(views::section(inputs, out)?);
    timed("calibrated views", t);
    let t = std::time::Instant::now();
    report.sections.push(photographs::section(out)?);
    timed("real photographs", t);
    let t = std::time::Instant::now();
    report.sections.push(layers::section(inputs, out)?);
    timed("layered projective textures", t);
    let t = std::time::Instant::now();
    report.sections.push(relief::section(inputs, out)?);
    timed("relief impostors", t);
    let t = std::time::Instant::now();
    report.sections.push(master::section(inputs, out)?);
    timed("master textures", t);
    io::write_png(&out.join(html::SCALE_FILE), &flip_scale()?)?;
    let mut run = Section::new("run", "This run");
    run.paragraph(format!(
        "Every figure above was measured while this page was written, in {:.1} s.",
        started.elapsed().as_secs_f64()
    ));
    run.table(steps);
    report.sections.push(run);
    let index = out.join("index.html");
    trompe::files::write_atomically(&index, report.to_html().as_bytes()).map_err(io_err(&index))?;
    summary.index = index;
    Ok(summary)
}

/// Makes `out` the report's directory: created if missing; else it must be empty or an
/// earlier report, so that no file of a user's is overwritten (`trompe::files::claim_folder`).
fn claim_directory(out: &Path) -> Result<(), ReportError> {
    Ok(trompe::files::claim_folder(
        out,
        trompe::files::FolderKind::DemoReport,
    )?)
}

/// `image` over a uniform `background` (alpha 0 shows it): how a blend with holes or a master
/// texture with unseen texels is shown beside a full image.
fn over(
    background: trompe::frame::Rgba,
    image: &trompe::frame::Image<trompe::frame::Rgba>,
) -> trompe::frame::Image<trompe::frame::Rgba> {
    image.map(|c| if c.w > 0.0 { c } else { background })
}

/// The FLIP colour scale, 0 on the left to 1 on the right.
/// Draws a line segment into an image (image coordinates), clipped to it.
pub(super) fn draw_line(
    img: &mut trompe::frame::Image<trompe::frame::Rgba>,
    a: glam::DVec2,
    b: glam::DVec2,
    color: trompe::frame::Rgba,
) {
    let steps = (b - a).abs().max_element().ceil().clamp(1.0, 1e5) as usize;
    let (w, h) = img.size();
    for i in 0..=steps {
        let p = a.lerp(b, i as f64 / steps as f64);
        if p.x >= 0.0 && p.y >= 0.0 && p.x < w as f64 && p.y < h as f64 {
            img.set(p.x as u32, p.y as u32, color);
        }
    }
}

fn flip_scale() -> Result<trompe::frame::Image<trompe::frame::Rgba>, FrameError> {
    let mut ramp = trompe::frame::Image::new(256, 1, 0.0f32)?;
    for x in 0..256 {
        ramp.set(x, 0, x as f32 / 255.0);
    }
    Ok(metrics::heat_map(&ramp))
}

/// Version, commit, machine, threads and date of this run.
fn metadata(inputs: &DemoInputs) -> Vec<(String, String)> {
    let root = inputs.scenes.parent().unwrap_or(Path::new("."));
    let commit = std::process::Command::new("git")
        .arg("-C")
        .arg(root)
        .args(["describe", "--always", "--dirty"])
        .output()
        .ok()
        .filter(|o| o.status.success())
        .map_or_else(
            || "unknown (not a git checkout)".to_string(),
            |o| String::from_utf8_lossy(&o.stdout).trim().to_string(),
        );
    let cpu = std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|c| {
            c.lines()
                .find_map(|l| l.strip_prefix("model name"))
                .map(|l| l.trim_start_matches([' ', '\t', ':']).to_string())
        })
        .unwrap_or_else(|| std::env::consts::ARCH.to_string());
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    vec![
        ("version".into(), env!("CARGO_PKG_VERSION").into()),
        ("commit".into(), commit),
        (
            "machine".into(),
            format!("{cpu}, {cores} cores, {}", std::env::consts::OS),
        ),
        ("threads".into(), rayon::current_num_threads().to_string()),
        ("date".into(), utc_now()),
    ]
}

/// The time now, UTC, as `YYYY-MM-DD HH:MM UTC`.
fn utc_now() -> String {
    let secs = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_secs());
    let (days, rem) = (secs / 86_400, secs % 86_400);
    // Civil date from days since 1970-01-01 (Howard Hinnant's algorithm).
    let z = days as i64 + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = doy - (153 * mp + 2) / 5 + 1;
    let m = if mp < 10 { mp + 3 } else { mp - 9 };
    let y = yoe + era * 400 + i64::from(m <= 2);
    format!(
        "{y:04}-{m:02}-{d:02} {:02}:{:02} UTC",
        rem / 3600,
        (rem % 3600) / 60
    )
}

fn fmt_psnr(p: f64) -> String {
    if p.is_infinite() {
        "∞".into()
    } else {
        format!("{p:.2}")
    }
}

impl std::fmt::Display for DemoSummary {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        for r in &self.renders {
            writeln!(
                f,
                "{:<12} {:<7} {:>8.0} ms  PSNR {:>6.2}  SSIM {:.4}  FLIP {:.4}  ids {:.2} %",
                r.scene,
                r.method.to_string(),
                r.time.as_secs_f64() * 1e3,
                r.scores.psnr,
                r.scores.ssim,
                r.scores.flip,
                r.id_agreement * 100.0
            )?;
        }
        write!(f, "wrote {}", self.index.display())
    }
}
