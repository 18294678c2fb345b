//! COLMAP's sparse model files: `cameras` and `images`, text (`.txt`) and binary (`.bin`), read
//! and written (text). Formats as COLMAP documents them (colmap.github.io, "Output format");
//! the fixtures under `tests/fixtures/colmap/` are written by COLMAP itself (pycolmap).
//!
//! Rigs and frames (COLMAP 3.12 and later, [`super::rig`]) are read when the model has them,
//! and pose every image a frame holds; `images` poses the others.

use super::{CalibratedView, CameraModel, Intrinsics, Pose, ViewsError};
use glam::{DQuat, DVec3};
use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

/// Largest model file trompe reads (a 100 000-image model is well under this).
const MAX_FILE_BYTES: u64 = 1 << 30;
/// A quaternion further than this from unit length is refused rather than normalised.
const UNIT_TOLERANCE: f64 = 1e-3;

/// The files of a COLMAP model in `dir` that [`read_model`] may read (for an output plan).
pub fn model_files(dir: &Path) -> Vec<std::path::PathBuf> {
    [
        "cameras.txt",
        "images.txt",
        "points3D.txt",
        "cameras.bin",
        "images.bin",
        "rigs.txt",
        "frames.txt",
        "rigs.bin",
        "frames.bin",
    ]
    .into_iter()
    .map(|f| dir.join(f))
    .collect()
}

/// Reads the model in `dir`: text when `cameras.txt` is there, else binary. Returns the views in
/// image-id order and warnings for what was skipped.
pub fn read_model(dir: &Path) -> Result<(Vec<CalibratedView>, Vec<String>), ViewsError> {
    read_model_summarized(dir).map(|(views, warnings, _)| (views, warnings))
}

/// What a model held, for a verbose report.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct ModelSummary {
    /// Text (`.txt`) or binary (`.bin`).
    pub text: bool,
    /// Cameras read.
    pub cameras: usize,
    /// Images read.
    pub images: usize,
    /// Rigs read (0 for a model from before COLMAP 3.12).
    pub rigs: usize,
    /// Frames read.
    pub frames: usize,
    /// Images posed through a frame.
    pub posed_by_frame: usize,
    /// Of the images posed through a frame, those through a sensor offset from the rig's
    /// reference.
    pub posed_by_offset: usize,
}

impl std::fmt::Display for ModelSummary {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{} model: {} cameras, {} images",
            if self.text { "text" } else { "binary" },
            self.cameras,
            self.images
        )?;
        if self.rigs + self.frames == 0 {
            return write!(f, "; no rigs or frames (every pose from images)");
        }
        write!(
            f,
            "; {} rigs, {} frames: {} images posed by their frame, {} of them through a \
             sensor's offset in its rig",
            self.rigs, self.frames, self.posed_by_frame, self.posed_by_offset
        )
    }
}

/// [`read_model`], with a summary of what was read.
pub fn read_model_summarized(
    dir: &Path,
) -> Result<(Vec<CalibratedView>, Vec<String>, ModelSummary), ViewsError> {
    let text = dir.join("cameras.txt").is_file();
    let (cameras, mut images) = if text {
        (
            read_cameras_text(&dir.join("cameras.txt"))?,
            read_images_text(&dir.join("images.txt"))?,
        )
    } else if dir.join("cameras.bin").is_file() {
        (
            read_cameras_binary(&dir.join("cameras.bin"))?,
            read_images_binary(&dir.join("images.bin"))?,
        )
    } else {
        return Err(ViewsError::NoModel(dir.to_path_buf()));
    };
    let mut summary = ModelSummary {
        text,
        cameras: cameras.len(),
        images: images.len(),
        ..ModelSummary::default()
    };
    let mut rig_warnings = Vec::new();
    if let Some(rigs) = super::rig::Rigs::read(dir, text)? {
        summary.rigs = rigs.rigs.len();
        summary.frames = rigs.frames.len();
        let posed = rigs.image_poses()?;
        let mut disagree = 0;
        for im in &mut images {
            let Some(p) = posed.get(&im.id) else { continue };
            if p.camera != im.camera {
                return Err(ViewsError::Malformed {
                    path: im.file.clone(),
                    element: im.element.clone(),
                    reason: format!(
                        "its camera is {}, but its frame holds it as camera {}'s",
                        im.camera, p.camera
                    ),
                });
            }
            let (a, b) = (&im.pose, &p.pose);
            if a.rotation.dot(b.rotation).abs() < 1.0 - 1e-9
                || (a.translation - b.translation).length() > 1e-6 * (1.0 + b.translation.length())
            {
                disagree += 1;
            }
            im.pose = p.pose;
            summary.posed_by_frame += 1;
            summary.posed_by_offset += p.offset as usize;
        }
        if disagree > 0 {
            rig_warnings.push(format!(
                "{disagree} images' poses in the images file disagree with their frames'; the \
                 frames' (rig pose and sensor offset) are used"
            ));
        }
    }
    let (views, mut warnings) = assemble(dir, cameras, images)?;
    warnings.extend(rig_warnings);
    let points = dir.join("points3D.txt");
    if points.is_file() {
        warnings.extend(check_points_text(&points, &views)?);
    }
    Ok((views, warnings, summary))
}

/// The sanity check `points3D.txt` allows: every observation of a 3-D point must see it in
/// front of the observing camera. Returns a warning when some do not (a model and poses that
/// disagree: a different frame, or inverted poses).
fn check_points_text(path: &Path, views: &[CalibratedView]) -> Result<Vec<String>, ViewsError> {
    let text = text_of(path)?;
    let by_id: BTreeMap<u32, &CalibratedView> = views.iter().map(|v| (v.image_id, v)).collect();
    let (mut observations, mut behind, mut unknown) = (0usize, 0usize, 0usize);
    for (n, line) in data_lines(&text) {
        let f: Vec<&str> = line.split_whitespace().collect();
        if f.len() < 8 || !(f.len() - 8).is_multiple_of(2) {
            return Err(malformed(
                path,
                format!("line {n}"),
                "expected POINT3D_ID X Y Z R G B ERROR and (IMAGE_ID, POINT2D_IDX) pairs",
            ));
        }
        let xyz = [
            parse::<f64>(path, n, "X", f[1])?,
            parse::<f64>(path, n, "Y", f[2])?,
            parse::<f64>(path, n, "Z", f[3])?,
        ];
        let p = DVec3::from_array(xyz);
        if !p.is_finite() {
            return Err(malformed(
                path,
                format!("line {n}"),
                "the point is not finite",
            ));
        }
        for pair in f[8..].chunks(2) {
            let image: u32 = parse(path, n, "image id", pair[0])?;
            observations += 1;
            match by_id.get(&image) {
                Some(v) if v.pose.to_camera(p).z <= 0.0 => behind += 1,
                Some(_) => {}
                None => unknown += 1,
            }
        }
    }
    let mut warnings = Vec::new();
    if behind > 0 {
        warnings.push(format!(
            "{}: {behind} of {observations} observations see their point behind the camera (poses and points disagree)",
            path.display()
        ));
    }
    if unknown > 0 {
        warnings.push(format!(
            "{}: {unknown} observations name an image the model does not hold",
            path.display()
        ));
    }
    Ok(warnings)
}

/// An image record before its camera is attached.
struct ImageRecord {
    id: u32,
    pose: Pose,
    camera: u32,
    name: String,
    /// Where it was read, for errors.
    element: String,
    file: std::path::PathBuf,
}

fn assemble(
    dir: &Path,
    cameras: BTreeMap<u32, Intrinsics>,
    images: Vec<ImageRecord>,
) -> Result<(Vec<CalibratedView>, Vec<String>), ViewsError> {
    let mut used = BTreeSet::new();
    let mut seen = BTreeSet::new();
    let mut views = Vec::with_capacity(images.len());
    for im in images {
        let Some(intrinsics) = cameras.get(&im.camera) else {
            return Err(ViewsError::Malformed {
                path: im.file,
                element: im.element,
                reason: format!("camera {} is not in the cameras file", im.camera),
            });
        };
        if !seen.insert(im.id) {
            return Err(ViewsError::Malformed {
                path: im.file,
                element: im.element,
                reason: format!("image id {} appears twice", im.id),
            });
        }
        used.insert(im.camera);
        views.push(CalibratedView {
            name: im.name,
            image_id: im.id,
            camera_id: im.camera,
            intrinsics: intrinsics.clone(),
            pose: im.pose,
            image: None,
        });
    }
    if views.is_empty() {
        return Err(ViewsError::Empty(dir.to_path_buf()));
    }
    views.sort_by_key(|v| v.image_id);
    let warnings = cameras
        .keys()
        .filter(|id| !used.contains(id))
        .map(|id| format!("camera {id}: no image uses it (skipped)"))
        .collect();
    Ok((views, warnings))
}

pub(super) fn read_bounded(path: &Path) -> Result<Vec<u8>, ViewsError> {
    use std::io::Read as _;
    let io = |source| ViewsError::Io {
        path: path.to_path_buf(),
        source,
    };
    let f = std::fs::File::open(path).map_err(io)?;
    let mut bytes = Vec::new();
    f.take(MAX_FILE_BYTES + 1)
        .read_to_end(&mut bytes)
        .map_err(io)?;
    if bytes.len() as u64 > MAX_FILE_BYTES {
        return Err(malformed(path, "file", "larger than 1 GiB"));
    }
    Ok(bytes)
}

pub(super) fn malformed(
    path: &Path,
    element: impl Into<String>,
    reason: impl Into<String>,
) -> ViewsError {
    ViewsError::Malformed {
        path: path.to_path_buf(),
        element: element.into(),
        reason: reason.into(),
    }
}

pub(super) fn pose_of(q: [f64; 4], t: [f64; 3]) -> Result<Pose, String> {
    if !q.iter().chain(&t).all(|v| v.is_finite()) {
        return Err("the pose is not finite".into());
    }
    let q = DQuat::from_xyzw(q[1], q[2], q[3], q[0]);
    let len = q.length();
    if (len - 1.0).abs() > UNIT_TOLERANCE {
        return Err(format!("the quaternion has length {len}, not 1"));
    }
    Ok(Pose {
        rotation: q / len,
        translation: DVec3::from_array(t),
    })
}

/// Lines that hold data: trimmed, neither empty nor comments, with their 1-based numbers.
pub(super) fn data_lines(text: &str) -> impl Iterator<Item = (usize, &str)> {
    text.lines()
        .enumerate()
        .map(|(i, l)| (i + 1, l.trim()))
        .filter(|(_, l)| !l.is_empty() && !l.starts_with('#'))
}

pub(super) fn text_of(path: &Path) -> Result<String, ViewsError> {
    String::from_utf8(read_bounded(path)?).map_err(|_| malformed(path, "file", "not UTF-8 text"))
}

pub(super) fn parse<T: std::str::FromStr>(
    path: &Path,
    line: usize,
    what: &str,
    s: &str,
) -> Result<T, ViewsError> {
    s.parse().map_err(|_| {
        malformed(
            path,
            format!("line {line}"),
            format!("{what} {s:?} is not a number"),
        )
    })
}

/// Reads `cameras.txt`: `CAMERA_ID MODEL WIDTH HEIGHT PARAMS[]` a line.
pub fn read_cameras_text(path: &Path) -> Result<BTreeMap<u32, Intrinsics>, ViewsError> {
    let text = text_of(path)?;
    let mut cameras = BTreeMap::new();
    for (n, line) in data_lines(&text) {
        let f: Vec<&str> = line.split_whitespace().collect();
        if f.len() < 4 {
            return Err(malformed(path, format!("line {n}"), "fewer than 4 fields"));
        }
        let id: u32 = parse(path, n, "camera id", f[0])?;
        let model = CameraModel::from_name(f[1]).ok_or_else(|| {
            malformed(
                path,
                format!("line {n}"),
                format!("camera model {} is not one trompe reads (SIMPLE_PINHOLE, PINHOLE, SIMPLE_RADIAL, RADIAL, OPENCV, FULL_OPENCV)", f[1]),
            )
        })?;
        let width: u32 = parse(path, n, "width", f[2])?;
        let height: u32 = parse(path, n, "height", f[3])?;
        let params = f[4..]
            .iter()
            .map(|s| parse::<f64>(path, n, "parameter", s))
            .collect::<Result<Vec<_>, _>>()?;
        add_camera(
            path,
            &mut cameras,
            id,
            model,
            (width as u64, height as u64),
            params,
        )?;
    }
    Ok(cameras)
}

/// Checks one camera record and adds it to `cameras` (text and binary models alike).
fn add_camera(
    path: &Path,
    cameras: &mut BTreeMap<u32, Intrinsics>,
    id: u32,
    model: CameraModel,
    (width, height): (u64, u64),
    params: Vec<f64>,
) -> Result<(), ViewsError> {
    let element = || format!("camera {id}");
    let (w, h) = crate::frame::check_size(width, height)
        .map_err(|e| malformed(path, element(), e.to_string()))?;
    let c = Intrinsics::new(model, w, h, params).map_err(|r| malformed(path, element(), r))?;
    if cameras.insert(id, c).is_some() {
        return Err(malformed(path, element(), "the id appears twice"));
    }
    Ok(())
}

/// Reads `images.txt`: two lines an image, `IMAGE_ID QW QX QY QZ TX TY TZ CAMERA_ID NAME`, then
/// its 2-D points (not used).
fn read_images_text(path: &Path) -> Result<Vec<ImageRecord>, ViewsError> {
    let text = text_of(path)?;
    let mut lines = text.lines().enumerate();
    let mut images = Vec::new();
    while let Some((i, line)) = lines.next() {
        let (n, line) = (i + 1, line.trim());
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        // The next line, whatever it holds, is this image's POINTS2D.
        lines.next();
        let f: Vec<&str> = line.split_whitespace().collect();
        if f.len() < 10 {
            return Err(malformed(path, format!("line {n}"), "fewer than 10 fields"));
        }
        let num = |k: usize, what: &str| parse::<f64>(path, n, what, f[k]);
        let id: u32 = parse(path, n, "image id", f[0])?;
        let q = [num(1, "QW")?, num(2, "QX")?, num(3, "QY")?, num(4, "QZ")?];
        let t = [num(5, "TX")?, num(6, "TY")?, num(7, "TZ")?];
        let pose = pose_of(q, t).map_err(|r| malformed(path, format!("image {id}"), r))?;
        images.push(ImageRecord {
            id,
            pose,
            camera: parse(path, n, "camera id", f[8])?,
            // A name may hold spaces: everything after the camera id.
            name: f[9..].join(" "),
            element: format!("image {id} (line {n})"),
            file: path.to_path_buf(),
        });
    }
    Ok(images)
}

/// A little-endian reader over a binary model that names the file in every error.
pub(super) struct Binary<'a> {
    pub(super) path: &'a Path,
    pub(super) bytes: &'a [u8],
    pub(super) at: usize,
}

impl Binary<'_> {
    pub(super) fn take(&mut self, n: usize, what: &str) -> Result<&[u8], ViewsError> {
        let end = self.at.checked_add(n).filter(|&e| e <= self.bytes.len());
        let Some(end) = end else {
            return Err(malformed(
                self.path,
                format!("byte {}", self.at),
                format!("truncated in {what}"),
            ));
        };
        let s = &self.bytes[self.at..end];
        self.at = end;
        Ok(s)
    }
    pub(super) fn u64(&mut self, what: &str) -> Result<u64, ViewsError> {
        let b = self.take(8, what)?;
        Ok(u64::from_le_bytes(b.try_into().unwrap_or_default()))
    }
    pub(super) fn u32(&mut self, what: &str) -> Result<u32, ViewsError> {
        let b = self.take(4, what)?;
        Ok(u32::from_le_bytes(b.try_into().unwrap_or_default()))
    }
    pub(super) fn f64(&mut self, what: &str) -> Result<f64, ViewsError> {
        let b = self.take(8, what)?;
        Ok(f64::from_le_bytes(b.try_into().unwrap_or_default()))
    }
    /// A count of records of at least `each` bytes, checked against the bytes left.
    pub(super) fn count(&mut self, each: usize, what: &str) -> Result<usize, ViewsError> {
        let n = self.u64(what)?;
        let left = (self.bytes.len() - self.at) as u64;
        if n.saturating_mul(each as u64) > left {
            return Err(malformed(
                self.path,
                what,
                format!("declares {n} records but {left} bytes remain"),
            ));
        }
        Ok(n as usize)
    }
}

/// Reads `cameras.bin`.
pub fn read_cameras_binary(path: &Path) -> Result<BTreeMap<u32, Intrinsics>, ViewsError> {
    let bytes = read_bounded(path)?;
    let mut r = Binary {
        path,
        bytes: &bytes,
        at: 0,
    };
    let n = r.count(24, "the camera count")?;
    let mut cameras = BTreeMap::new();
    for _ in 0..n {
        let id = r.u32("a camera id")?;
        let model_id = r.u32("a camera model")? as i32;
        let model = CameraModel::from_id(model_id).ok_or_else(|| {
            malformed(
                path,
                format!("camera {id}"),
                format!("camera model id {model_id} is not one trompe reads"),
            )
        })?;
        let (width, height) = (r.u64("a width")?, r.u64("a height")?);
        let params = (0..model.param_count())
            .map(|_| r.f64("camera parameters"))
            .collect::<Result<Vec<_>, _>>()?;
        add_camera(path, &mut cameras, id, model, (width, height), params)?;
    }
    Ok(cameras)
}

/// Reads `images.bin` (the 2-D points are skipped).
fn read_images_binary(path: &Path) -> Result<Vec<ImageRecord>, ViewsError> {
    let bytes = read_bounded(path)?;
    let mut r = Binary {
        path,
        bytes: &bytes,
        at: 0,
    };
    let n = r.count(4 + 7 * 8 + 4 + 1 + 8, "the image count")?;
    let mut images = Vec::with_capacity(n);
    for _ in 0..n {
        let id = r.u32("an image id")?;
        let mut q = [0.0; 4];
        for v in &mut q {
            *v = r.f64("a rotation")?;
        }
        let mut t = [0.0; 3];
        for v in &mut t {
            *v = r.f64("a translation")?;
        }
        let camera = r.u32("a camera id")?;
        let rest = &r.bytes[r.at..];
        let Some(len) = rest.iter().position(|&b| b == 0) else {
            return Err(malformed(
                path,
                format!("image {id}"),
                "its name is not terminated",
            ));
        };
        let name = String::from_utf8(rest[..len].to_vec())
            .map_err(|_| malformed(path, format!("image {id}"), "its name is not UTF-8"))?;
        r.at += len + 1;
        let points = r.count(24, "a 2-D point count")?;
        r.take(points * 24, "2-D points")?;
        let pose =
            pose_of(q, t).map_err(|reason| malformed(path, format!("image {id}"), reason))?;
        images.push(ImageRecord {
            id,
            pose,
            camera,
            name,
            element: format!("image {id}"),
            file: path.to_path_buf(),
        });
    }
    Ok(images)
}

/// Writes `views` as a COLMAP text model (`cameras.txt`, `images.txt`, an empty
/// `points3D.txt`) into `dir`, each file replaced whole.
pub fn write_text(dir: &Path, views: &[CalibratedView]) -> Result<(), ViewsError> {
    use std::fmt::Write as _;
    let mut cameras: BTreeMap<u32, &Intrinsics> = BTreeMap::new();
    for v in views {
        cameras.insert(v.camera_id, &v.intrinsics);
    }
    let mut text = String::from(
        "# Camera list with one line of data per camera:\n#   CAMERA_ID, MODEL, WIDTH, HEIGHT, PARAMS[]\n",
    );
    let _ = writeln!(text, "# Number of cameras: {}", cameras.len());
    for (id, c) in &cameras {
        let (w, h) = c.size();
        let _ = write!(text, "{id} {} {w} {h}", c.model().name());
        for p in c.params() {
            let _ = write!(text, " {p:?}");
        }
        text.push('\n');
    }
    let mut images = String::from(
        "# Image list with two lines of data per image:\n#   IMAGE_ID, QW, QX, QY, QZ, TX, TY, TZ, CAMERA_ID, NAME\n#   POINTS2D[] as (X, Y, POINT3D_ID)\n",
    );
    let _ = writeln!(images, "# Number of images: {}", views.len());
    for v in views {
        let (q, t) = (v.pose.rotation, v.pose.translation);
        let _ = writeln!(
            images,
            "{} {:?} {:?} {:?} {:?} {:?} {:?} {:?} {} {}\n",
            v.image_id, q.w, q.x, q.y, q.z, t.x, t.y, t.z, v.camera_id, v.name
        );
    }
    let points = "# 3D point list with one line of data per point:\n#   POINT3D_ID, X, Y, Z, R, G, B, ERROR, TRACK[] as (IMAGE_ID, POINT2D_IDX)\n# Number of points: 0\n";
    for (name, body) in [
        ("cameras.txt", text.as_str()),
        ("images.txt", images.as_str()),
        ("points3D.txt", points),
    ] {
        let path = dir.join(name);
        crate::files::write_atomically(&path, body.as_bytes())
            .map_err(|source| ViewsError::Io { path, source })?;
    }
    Ok(())
}
