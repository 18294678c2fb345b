//! COLMAP's rigs and frames (COLMAP 3.12 and later, the default in 4): a rig is a set of sensors
//! with fixed poses relative to its reference sensor (`sensor_from_rig`), a frame one instant of
//! a rig (`rig_from_world`) and the measurements its sensors took then — for a camera, an image.
//! An image's pose is composed as `cam_from_world = sensor_from_rig · rig_from_world`, the
//! reference sensor's `sensor_from_rig` being the identity. Formats as COLMAP writes them
//! (`rigs.txt` / `rigs.bin`, `frames.txt` / `frames.bin`); the fixtures under
//! `tests/fixtures/colmap/` are written by COLMAP itself (pycolmap).
//!
//! Invariant: an image that a frame holds is posed by its frame and its rig, or the model is
//! refused, naming the rig or frame that cannot pose it; never posed silently otherwise.

use super::colmap::{Binary, data_lines, malformed, parse, pose_of, read_bounded, text_of};
use super::{Pose, ViewsError};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// A sensor of a rig: its kind (COLMAP's `SensorType`: 0 a camera, 1 an IMU) and id (for a
/// camera, its camera id).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub struct Sensor {
    /// COLMAP's sensor type.
    pub kind: i32,
    /// The sensor's id among those of its kind.
    pub id: u32,
}

/// COLMAP's sensor type of a camera.
const CAMERA: i32 = 0;
/// COLMAP's sensor type of an IMU.
const IMU: i32 = 1;

impl std::fmt::Display for Sensor {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self.kind {
            CAMERA => write!(f, "CAMERA {}", self.id),
            IMU => write!(f, "IMU {}", self.id),
            k => write!(f, "sensor type {k} {}", self.id),
        }
    }
}

/// One rig: its reference sensor and every other sensor's `sensor_from_rig` (`None`: not
/// calibrated).
#[derive(Clone, Debug, PartialEq)]
pub struct Rig {
    /// The sensor that defines the rig's frame.
    pub reference: Option<Sensor>,
    /// The other sensors and their poses relative to the rig.
    pub sensors: BTreeMap<Sensor, Option<Pose>>,
}

/// One frame: its rig, the rig's pose, and what each sensor measured (for a camera, an image id).
#[derive(Clone, Debug, PartialEq)]
pub struct Frame {
    /// The frame's id.
    pub id: u32,
    /// Its rig's id.
    pub rig: u32,
    /// `rig_from_world`.
    pub rig_from_world: Pose,
    /// The measurements: sensor and data id.
    pub data: Vec<(Sensor, u64)>,
}

/// A model's rigs and frames, with the files they were read from (for errors).
#[derive(Clone, Debug)]
pub struct Rigs {
    /// Rigs by id.
    pub rigs: BTreeMap<u32, Rig>,
    /// Frames in file order.
    pub frames: Vec<Frame>,
    rigs_file: PathBuf,
    frames_file: PathBuf,
}

/// An image pose composed through its frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Posed {
    /// `cam_from_world`.
    pub pose: Pose,
    /// The camera (sensor id) that took it.
    pub camera: u32,
    /// Whether the camera is not its rig's reference (its pose carries a `sensor_from_rig`).
    pub offset: bool,
}

/// `a · b`: first `b`, then `a`.
pub fn compose(a: &Pose, b: &Pose) -> Pose {
    Pose {
        rotation: a.rotation * b.rotation,
        translation: a.rotation * b.translation + a.translation,
    }
}

impl Rigs {
    /// Reads the rigs and frames beside a model's other files in `dir`, text or binary as
    /// `text` says; `None` when the model has neither file (a model from before COLMAP 3.12).
    pub fn read(dir: &Path, text: bool) -> Result<Option<Rigs>, ViewsError> {
        let ext = if text { "txt" } else { "bin" };
        let (rigs_file, frames_file) = (
            dir.join(format!("rigs.{ext}")),
            dir.join(format!("frames.{ext}")),
        );
        match (rigs_file.is_file(), frames_file.is_file()) {
            (false, false) => return Ok(None),
            (true, false) => {
                return Err(malformed(
                    &frames_file,
                    "file",
                    "missing, though the model has rigs: its images' poses cannot be composed",
                ));
            }
            (false, true) => {
                return Err(malformed(
                    &rigs_file,
                    "file",
                    "missing, though the model has frames: their rigs are unknown",
                ));
            }
            (true, true) => {}
        }
        let (rigs, frames) = if text {
            (read_rigs_text(&rigs_file)?, read_frames_text(&frames_file)?)
        } else {
            (
                read_rigs_binary(&rigs_file)?,
                read_frames_binary(&frames_file)?,
            )
        };
        Ok(Some(Rigs {
            rigs,
            frames,
            rigs_file,
            frames_file,
        }))
    }

    /// Every image a frame holds, by image id, posed through its frame and rig. An image held
    /// by two frames, a frame whose rig is unknown, a camera its rig does not hold and a camera
    /// whose pose in its rig is not calibrated are errors naming the frame or rig.
    pub fn image_poses(&self) -> Result<BTreeMap<u32, Posed>, ViewsError> {
        let mut out = BTreeMap::new();
        for frame in &self.frames {
            let element = || format!("frame {}", frame.id);
            let Some(rig) = self.rigs.get(&frame.rig) else {
                return Err(malformed(
                    &self.frames_file,
                    element(),
                    format!(
                        "its rig {} is not in {}",
                        frame.rig,
                        self.rigs_file.display()
                    ),
                ));
            };
            for &(sensor, data) in &frame.data {
                if sensor.kind != CAMERA {
                    continue;
                }
                let image = u32::try_from(data).map_err(|_| {
                    malformed(
                        &self.frames_file,
                        element(),
                        format!("image id {data} is out of range"),
                    )
                })?;
                let (pose, offset) = if rig.reference == Some(sensor) {
                    (frame.rig_from_world, false)
                } else {
                    match rig.sensors.get(&sensor) {
                        Some(Some(sensor_from_rig)) => {
                            (compose(sensor_from_rig, &frame.rig_from_world), true)
                        }
                        Some(None) => {
                            return Err(malformed(
                                &self.rigs_file,
                                format!("rig {}", frame.rig),
                                format!(
                                    "{sensor} has no calibrated pose in the rig, so image \
                                     {image} of frame {} cannot be posed",
                                    frame.id
                                ),
                            ));
                        }
                        None => {
                            return Err(malformed(
                                &self.frames_file,
                                element(),
                                format!("{sensor} is not a sensor of its rig {}", frame.rig),
                            ));
                        }
                    }
                };
                let posed = Posed {
                    pose,
                    camera: sensor.id,
                    offset,
                };
                if out.insert(image, posed).is_some() {
                    return Err(malformed(
                        &self.frames_file,
                        element(),
                        format!("image {image} is held by an earlier frame too"),
                    ));
                }
            }
        }
        Ok(out)
    }
}

/// A sensor type from its text name.
fn sensor_kind(path: &Path, line: usize, name: &str) -> Result<i32, ViewsError> {
    match name {
        "CAMERA" => Ok(CAMERA),
        "IMU" => Ok(IMU),
        _ => Err(malformed(
            path,
            format!("line {line}"),
            format!("unknown sensor type {name:?} (CAMERA or IMU)"),
        )),
    }
}

/// A pose written as `QW QX QY QZ TX TY TZ`.
fn text_pose(path: &Path, line: usize, f: &[&str]) -> Result<Pose, ViewsError> {
    let mut v = [0.0; 7];
    for (i, s) in f.iter().enumerate().take(7) {
        v[i] = parse(path, line, "a pose value", s)?;
    }
    pose_of([v[0], v[1], v[2], v[3]], [v[4], v[5], v[6]])
        .map_err(|reason| malformed(path, format!("line {line}"), reason))
}

/// Reads `rigs.txt`: `RIG_ID NUM_SENSORS REF_SENSOR_TYPE REF_SENSOR_ID` and, for each other
/// sensor, `SENSOR_TYPE SENSOR_ID HAS_POSE [QW QX QY QZ TX TY TZ]`.
fn read_rigs_text(path: &Path) -> Result<BTreeMap<u32, Rig>, ViewsError> {
    let text = text_of(path)?;
    let mut rigs = BTreeMap::new();
    for (n, line) in data_lines(&text) {
        let f: Vec<&str> = line.split_whitespace().collect();
        let short = || malformed(path, format!("line {n}"), "the line ends early");
        if f.len() < 2 {
            return Err(short());
        }
        let id: u32 = parse(path, n, "the rig id", f[0])?;
        let count: usize = parse(path, n, "the sensor count", f[1])?;
        let mut rig = Rig {
            reference: None,
            sensors: BTreeMap::new(),
        };
        let mut at = 2;
        if count > 0 {
            let (kind, sid) = (
                f.get(at).ok_or_else(short)?,
                f.get(at + 1).ok_or_else(short)?,
            );
            rig.reference = Some(Sensor {
                kind: sensor_kind(path, n, kind)?,
                id: parse(path, n, "the reference sensor id", sid)?,
            });
            at += 2;
        }
        for _ in 1..count.max(1) {
            let head = f.get(at..at + 3).ok_or_else(short)?;
            let sensor = Sensor {
                kind: sensor_kind(path, n, head[0])?,
                id: parse(path, n, "a sensor id", head[1])?,
            };
            at += 3;
            let pose = match head[2] {
                "0" => None,
                "1" => {
                    let p = text_pose(path, n, f.get(at..at + 7).ok_or_else(short)?)?;
                    at += 7;
                    Some(p)
                }
                other => {
                    return Err(malformed(
                        path,
                        format!("line {n}"),
                        format!("HAS_POSE {other:?} is neither 0 nor 1"),
                    ));
                }
            };
            rig.sensors.insert(sensor, pose);
        }
        if at != f.len() {
            return Err(malformed(
                path,
                format!("line {n}"),
                format!("{} values after the {count} sensors", f.len() - at),
            ));
        }
        if rigs.insert(id, rig).is_some() {
            return Err(malformed(
                path,
                format!("line {n}"),
                format!("rig {id} appears twice"),
            ));
        }
    }
    Ok(rigs)
}

/// Reads `frames.txt`: `FRAME_ID RIG_ID QW QX QY QZ TX TY TZ NUM_DATA_IDS` and that many
/// `SENSOR_TYPE SENSOR_ID DATA_ID`.
fn read_frames_text(path: &Path) -> Result<Vec<Frame>, ViewsError> {
    let text = text_of(path)?;
    let mut frames = Vec::new();
    for (n, line) in data_lines(&text) {
        let f: Vec<&str> = line.split_whitespace().collect();
        if f.len() < 10 {
            return Err(malformed(
                path,
                format!("line {n}"),
                "expected FRAME_ID RIG_ID QW QX QY QZ TX TY TZ NUM_DATA_IDS",
            ));
        }
        let id: u32 = parse(path, n, "the frame id", f[0])?;
        let rig: u32 = parse(path, n, "the rig id", f[1])?;
        let rig_from_world = text_pose(path, n, &f[2..9])?;
        let count: usize = parse(path, n, "the data count", f[9])?;
        if f.len() != 10 + 3 * count.min(f.len()) {
            return Err(malformed(
                path,
                format!("line {n}"),
                format!("{count} data ids declared, {} values follow", f.len() - 10),
            ));
        }
        let mut data = Vec::with_capacity(count);
        for d in f[10..].chunks(3) {
            data.push((
                Sensor {
                    kind: sensor_kind(path, n, d[0])?,
                    id: parse(path, n, "a sensor id", d[1])?,
                },
                parse(path, n, "a data id", d[2])?,
            ));
        }
        frames.push(Frame {
            id,
            rig,
            rig_from_world,
            data,
        });
    }
    Ok(frames)
}

/// A pose in a binary model: `QW QX QY QZ TX TY TZ` as doubles.
fn binary_pose(r: &mut Binary, element: &str) -> Result<Pose, ViewsError> {
    let mut v = [0.0; 7];
    for x in &mut v {
        *x = r.f64("a pose")?;
    }
    pose_of([v[0], v[1], v[2], v[3]], [v[4], v[5], v[6]])
        .map_err(|reason| malformed(r.path, element, reason))
}

/// A sensor in a binary model: its type (`int32`) and id (`uint32`).
fn binary_sensor(r: &mut Binary, element: &str) -> Result<Sensor, ViewsError> {
    let kind = r.u32("a sensor type")? as i32;
    if kind != CAMERA && kind != IMU {
        return Err(malformed(
            r.path,
            element,
            format!("unknown sensor type {kind}"),
        ));
    }
    Ok(Sensor {
        kind,
        id: r.u32("a sensor id")?,
    })
}

/// Reads `rigs.bin`: a `uint64` count, then per rig `rig_id`, `num_sensors` (`uint32`), the
/// reference sensor when there is one, and per other sensor its sensor, a `has_pose` byte and
/// the pose when set.
fn read_rigs_binary(path: &Path) -> Result<BTreeMap<u32, Rig>, ViewsError> {
    let bytes = read_bounded(path)?;
    let mut r = Binary {
        path,
        bytes: &bytes,
        at: 0,
    };
    let n = r.count(8, "the rig count")?;
    let mut rigs = BTreeMap::new();
    for _ in 0..n {
        let id = r.u32("a rig id")?;
        let element = format!("rig {id}");
        let count = r.u32("a sensor count")? as usize;
        if count.saturating_mul(8) > r.bytes.len() - r.at {
            return Err(malformed(
                path,
                element,
                format!("declares {count} sensors, more than the file holds"),
            ));
        }
        let mut rig = Rig {
            reference: None,
            sensors: BTreeMap::new(),
        };
        if count > 0 {
            rig.reference = Some(binary_sensor(&mut r, &element)?);
        }
        for _ in 1..count.max(1) {
            let sensor = binary_sensor(&mut r, &element)?;
            let pose = match r.take(1, "a has_pose flag")?[0] {
                0 => None,
                1 => Some(binary_pose(&mut r, &element)?),
                b => {
                    return Err(malformed(
                        path,
                        element,
                        format!("has_pose byte {b} is neither 0 nor 1"),
                    ));
                }
            };
            rig.sensors.insert(sensor, pose);
        }
        if rigs.insert(id, rig).is_some() {
            return Err(malformed(path, element, "the rig appears twice"));
        }
    }
    Ok(rigs)
}

/// Reads `frames.bin`: a `uint64` count, then per frame `frame_id`, `rig_id` (`uint32`), the
/// pose, `num_data_ids` (`uint32`) and per data id its sensor and a `uint64` data id.
fn read_frames_binary(path: &Path) -> Result<Vec<Frame>, ViewsError> {
    let bytes = read_bounded(path)?;
    let mut r = Binary {
        path,
        bytes: &bytes,
        at: 0,
    };
    let n = r.count(4 + 4 + 7 * 8 + 4, "the frame count")?;
    let mut frames = Vec::with_capacity(n);
    for _ in 0..n {
        let id = r.u32("a frame id")?;
        let element = format!("frame {id}");
        let rig = r.u32("a rig id")?;
        let rig_from_world = binary_pose(&mut r, &element)?;
        let count = r.u32("a data count")? as usize;
        if count.saturating_mul(16) > r.bytes.len() - r.at {
            return Err(malformed(
                path,
                element,
                format!("declares {count} data ids, more than the file holds"),
            ));
        }
        let mut data = Vec::with_capacity(count);
        for _ in 0..count {
            let sensor = binary_sensor(&mut r, &element)?;
            data.push((sensor, r.u64("a data id")?));
        }
        frames.push(Frame {
            id,
            rig,
            rig_from_world,
            data,
        });
    }
    Ok(frames)
}
