//! Section "Real photographs" (papers 4 and 5 are about photographs): Middlebury's rectified
//! "Aloe" pair, as Debian's opencv-doc ships it, written as COLMAP models, a mesh of the left
//! image's true disparity and a forward-warp baseline by `tests/fixtures/stereo/make_pair.py`;
//! the right camera rendered from the left photograph alone, with and without the prefilter,
//! scored beside the baseline against the right photograph (docs/views.md); and both
//! photographs, one a stop darker, baked seamlessly (docs/master.md). Without the
//! packages the section says what to install — or fails, where `TROMPE_REQUIRE_SYSTEM` is set.

use super::html::{Figure, Section, Table};
use super::{ReportError, io_err};
use std::path::{Path, PathBuf};
use trompe::frame::metrics::{self, Scores};
use trompe::frame::{Image, Rgba, io};
use trompe::views::{BlendSettings, ViewSet, blend, visibility::DepthMap};

/// Where opencv-doc puts the pair.
const DATA: &str = "/usr/share/doc/opencv-doc/examples/data";

/// The script that writes the pair, in the repository this binary was built from.
fn script() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/fixtures/stereo/make_pair.py")
}

/// A Python that imports OpenCV: `python3` on the `PATH`, or the system's.
fn python() -> Option<&'static str> {
    ["python3", "/usr/bin/python3"].into_iter().find(|p| {
        std::process::Command::new(p)
            .args(["-c", "import cv2, numpy"])
            .output()
            .is_ok_and(|o| o.status.success())
    })
}

/// Writes the pair into `dir` (a working folder inside the report, which `demo` has claimed
/// as its own, emptied first) with `make_pair.py`'s options `args`; returns `dir`.
fn make_pair(python: &str, dir: &Path, args: &[&str]) -> Result<PathBuf, ReportError> {
    if dir.exists() {
        std::fs::remove_dir_all(dir).map_err(io_err(dir))?;
    }
    let made = std::process::Command::new(python)
        .arg(script())
        .arg(dir)
        .args(args)
        .output()
        .map_err(io_err(dir))?;
    if !made.status.success() {
        return Err(ReportError::Io {
            path: script(),
            source: std::io::Error::other(String::from_utf8_lossy(&made.stderr).into_owned()),
        });
    }
    Ok(dir.to_path_buf())
}

pub(super) fn section(out: &Path) -> Result<Section, ReportError> {
    let mut s = Section::new("photographs", "Real photographs");
    let python = python();
    let ready = Path::new(DATA).join("aloeGT.png").is_file() && script().is_file();
    let (Some(python), true) = (python, ready) else {
        let missing = "the Aloe pair (Debian: opencv-doc), python3 with OpenCV (python3-opencv) \
                       and tests/fixtures/stereo/make_pair.py";
        if std::env::var_os("TROMPE_REQUIRE_SYSTEM").is_some() {
            return Err(ReportError::Io {
                path: PathBuf::from(DATA),
                source: std::io::Error::other(format!(
                    "the real-photograph section needs {missing}, and TROMPE_REQUIRE_SYSTEM is set"
                )),
            });
        }
        s.paragraph(format!("Not measured here: this section needs {missing}."));
        return Ok(s);
    };
    // The pair's models, mesh and baseline, removed once the figures are written.
    let dir = make_pair(
        python,
        &out.join("photographs"),
        &["--scale", "0.5", "--render-scale", "0.5"],
    )?;
    let mut left = ViewSet::load(&dir.join("left"), Some(&dir.join("images")))?;
    left.load_images()?;
    let mesh_file = dir.join("mesh.obj");
    let mesh = trompe::geom::io::load(&mesh_file)?.mesh;
    let right = trompe::views::camera_of(&dir.join("right"), "aloeR.png", 1e-3, false)?;
    let camera = right.at(0.0)?;
    let depth = DepthMap::of_all(&left.views, &mesh)?;
    let read = |p: PathBuf| io::read_color(&p);
    let truth = read(dir.join("images/aloeR.png"))?;
    let warp = read(dir.join("baseline.png"))?;
    let mut renders = Vec::new();
    for prefilter in [true, false] {
        let settings = BlendSettings {
            prefilter,
            ..BlendSettings::default()
        };
        let b = blend::render(&camera, &mesh, &left.views, &depth, &settings, None)?;
        renders.push(b.image);
    }
    // Scored where every picture covers the surface.
    let mut both: Image<bool> = truth.map(|_| true);
    for (i, m) in both.pixels_mut().iter_mut().enumerate() {
        *m = renders
            .iter()
            .chain([&warp])
            .all(|img| img.pixels()[i].w > 0.0);
    }
    let score = |img: &Image<Rgba>| metrics::compare(&truth, img, Some(&both));
    let mut table = Table::new(["the right camera", "PSNR (dB)", "SSIM", "FLIP"]);
    let row = |t: &mut Table, what: &str, s: &Scores| {
        t.row([
            what.to_string(),
            format!("{:.2}", s.psnr),
            format!("{:.4}", s.ssim),
            format!("{:.4}", s.flip),
        ]);
    };
    row(
        &mut table,
        "`views render --prefilter`",
        &score(&renders[0])?,
    );
    row(
        &mut table,
        "`views render` (one lookup a view)",
        &score(&renders[1])?,
    );
    row(
        &mut table,
        "forward warp by the true disparity (nearest splat)",
        &score(&warp)?,
    );
    let covered = both.pixels().iter().filter(|&&b| b).count();
    let (w, h) = truth.size();
    s.paragraph(format!(
        "Middlebury's rectified \"Aloe\" pair with its true disparity (Scharstein and Pal, CVPR \
         2007), from Debian's opencv-doc, at half size; the right camera rendered at half that \
         ({w} × {h}) from the left photograph alone through the mesh of the left image's true \
         disparity, and scored against the right photograph on the {covered} pixels every \
         picture covers. The baseline forward-warps the left photograph into the right camera by \
         the same disparity, nearest splat. Written by `tests/fixtures/stereo/make_pair.py`; \
         docs/views.md has the table at other sizes."
    ));
    s.table(table);
    let mut figures = Vec::new();
    for (file, image, caption) in [
        ("photographs-truth.png", &truth, "the right photograph"),
        (
            "photographs-prefilter.png",
            &renders[0],
            "rendered from the left one, prefiltered",
        ),
        ("photographs-warp.png", &warp, "the forward warp"),
    ] {
        io::write_png(&out.join(file), image)?;
        figures.push(Figure::new(file, caption));
    }
    s.figures(figures);
    std::fs::remove_dir_all(&dir).map_err(io_err(&dir))?;
    seams(&mut s, python, out)?;
    Ok(s)
}

/// Both photographs at a quarter size, the right one a stop darker, baked view-independently
/// by `master encode` and by the views' seamless best-face bake: the step across seams with
/// the views' gains alone (the global levelling) and levelled.
fn seams(s: &mut Section, python: &str, out: &Path) -> Result<(), ReportError> {
    let dir = make_pair(
        python,
        &out.join("photographs-seams"),
        &["--scale", "0.25", "--exposure", "0.5"],
    )?;
    let (both, images) = (dir.join("both"), dir.join("images"));
    let mesh = trompe::geom::io::load(&dir.join("mesh.obj"))?.mesh;
    let encoded = trompe::master::job::encode_folder(
        &both,
        Some(&images),
        &mesh,
        Some(1.0),
        &dir.join("encoded"),
        &(),
    )?;
    let mut set = ViewSet::load(&both, Some(&images))?;
    set.load_images()?;
    let depth = DepthMap::of_all(&set.views, &mesh)?;
    let settings = BlendSettings {
        weighting: trompe::views::Weighting::BestFace,
        seamless: true,
        ..BlendSettings::default()
    };
    let camera = set.views[0].pinhole();
    let render = blend::render(&camera, &mesh, &set.views, &depth, &settings, None)?;
    let mut table = Table::new([
        "bake",
        "seam edges",
        "step, gains alone (levels)",
        "step, levelled (levels)",
    ]);
    for (what, r) in [
        ("`master encode`'s bake.png", Some(encoded.bake.seams)),
        (
            "`views render --weights best-face --seamless`",
            render.seams,
        ),
    ] {
        let Some(r) = r else { continue };
        table.row([
            what.to_string(),
            r.edges.to_string(),
            format!("{:.2}", r.step_gains),
            format!("{:.2}", r.step_levelled),
        ]);
    }
    s.paragraph(
        "Seamless bakes: both photographs of the pair at a quarter size, the right one a stop \
         darker (its exposure halved in linear light, by `make_pair.py --exposure 0.5`), baked \
         view-independently. Each view's texels take one gain a channel (the global levelling); \
         then per-vertex offsets solved on the mesh level the seams where faces from the two \
         photographs meet. The step is the mean colour difference across seams, in 8-bit sRGB \
         levels (docs/master.md)."
            .to_string(),
    );
    s.table(table);
    std::fs::remove_dir_all(&dir).map_err(io_err(&dir))?;
    Ok(())
}
