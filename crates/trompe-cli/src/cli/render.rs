//! `trompe render SCENE`: one frame, or with `--frames` a sequence, of a scene by any method of
//! the library's list (`trompe::methods`) — parse, prepare the method, ask it for frames, write
//! the images, print the timings and, for a sequence, a line a frame.

use super::{MAX_IMPOSTOR_SIDE, MethodArg, bar, check_plan, print_timings};
use anyhow::{Context, Result, bail};
use clap::ValueEnum;
use std::path::{Path, PathBuf};
use trompe::files::OutputPlan;
use trompe::frame::{io, metrics};
use trompe::methods::{MethodKind, MethodSettings, Renderer};
use trompe::render::{self, Timings};
use trompe::scene::Scene;
use trompe_gpu::DeviceRenderer;

/// `trompe render`.
#[derive(clap::Args, Debug)]
pub struct RenderArgs {
    /// Scene file (TOML; see scenes/README.md).
    scene: PathBuf,
    /// Output image: .png (sRGB) or .exr (linear float). With --frames, a pattern holding
    /// `%04d` (or `%d`, `%05d` …) that the frame number replaces: `out/frame_%04d.png`.
    #[arg(short, long)]
    output: PathBuf,
    /// Renderer.
    #[arg(long, value_enum, default_value = "trace")]
    method: MethodArg,
    #[command(flatten)]
    camera: super::views::CameraArg,
    /// Where the method runs: the CPU; the GPU (a hardware adapter, else a software one such
    /// as Mesa's lavapipe; refused for a method without a GPU path); or auto (the GPU where
    /// the method has a path and a hardware GPU is present, else the CPU).
    #[arg(long, value_enum, default_value_t = DeviceArg::Cpu)]
    device: DeviceArg,
    /// How glass refracts what the eye sees through it: traced through the object, or by
    /// Wyman's image-space approximation of its far side (trace, impostor, pinhole-impostor and
    /// envmap methods).
    #[arg(long, value_enum, default_value_t = RefractionArg::Exact)]
    refraction: RefractionArg,
    /// How mirrors see other mirrors under --method impostor and pinhole-impostor: traced
    /// exactly, or as impostors that store their normals (paper 1's inter-reflections).
    #[arg(long, value_enum, default_value_t = MirrorsArg::Exact)]
    mirrors: MirrorsArg,
    /// What finds the surfaces the eye sees, for the ray-tracing methods: a ray a pixel
    /// through the BVH, or the rasterizer's visibility buffer (faster; differs on silhouette
    /// pixels only).
    #[arg(long, value_enum, default_value_t = PrimaryArg::Traced)]
    primary: PrimaryArg,
    /// Impostor resolution (square), for --method impostor and pinhole-impostor.
    #[arg(long, default_value_t = render::DEFAULT_IMPOSTOR_RESOLUTION,
          value_parser = clap::value_parser!(u32).range(1..=MAX_IMPOSTOR_SIDE))]
    impostor_resolution: u32,
    /// Frames a side of each object's atlas, for --method octahedral.
    #[arg(long, default_value_t = 16, value_parser = clap::value_parser!(u32).range(2..=64))]
    octahedral: u32,
    /// Texels a side of each atlas frame, for --method octahedral.
    #[arg(long, default_value_t = 128, value_parser = clap::value_parser!(u32).range(4..=1024))]
    frame_size: u32,
    /// Splat side in pixels, for --method c3rc.
    #[arg(long, default_value_t = 2, value_parser = clap::value_parser!(u32).range(1..=2))]
    splat: u32,
    /// Point spacing in scene units, for --method c3rc; default: derived per object from its
    /// closest reflection distance.
    #[arg(long)]
    spacing: Option<f32>,
    /// Time in seconds (camera path and animation); default: the scene's. With --frames, the
    /// first frame's.
    #[arg(long)]
    time: Option<f32>,
    /// Render this many frames, `1 / fps` seconds apart, into the files -o names; impostors
    /// are kept across rigid motion and rebuilt for deforming objects.
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=100_000))]
    frames: Option<u32>,
    /// Frames a second of scene time, with --frames.
    #[arg(long, default_value_t = 30.0, requires = "frames")]
    fps: f32,
    /// With --frames: also trace every frame exactly and print its FLIP and PSNR against it.
    #[arg(long, requires = "frames")]
    compare: bool,
    /// Also write the depth (distance) as a float EXR.
    #[arg(long)]
    depth: Option<PathBuf>,
    /// Also write the shading normals as a float EXR.
    #[arg(long)]
    normals: Option<PathBuf>,
}

/// `--device`.
#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum DeviceArg {
    /// The library's CPU path.
    Cpu,
    /// The GPU path.
    Gpu,
    /// The GPU where it pays and is present, else the CPU.
    Auto,
}

impl From<DeviceArg> for trompe_gpu::Device {
    fn from(d: DeviceArg) -> Self {
        match d {
            DeviceArg::Cpu => trompe_gpu::Device::Cpu,
            DeviceArg::Gpu => trompe_gpu::Device::Gpu,
            DeviceArg::Auto => trompe_gpu::Device::Auto,
        }
    }
}

/// `--refraction`.
#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum RefractionArg {
    /// Both interfaces traced.
    Exact,
    /// Wyman's image-space approximation (SIGGRAPH 2005).
    Wyman,
}

/// `--primary`.
#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum PrimaryArg {
    /// A ray a pixel through the BVH.
    Traced,
    /// The rasterizer's visibility buffer.
    Rasterized,
}

/// `--mirrors`.
#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum MirrorsArg {
    /// Mirror-to-mirror rays traced through a BVH of the mirrors and glass.
    Exact,
    /// Other mirrors seen as impostors storing their normals; the ray reflects on.
    Impostor,
}

/// Writes a rendered frame: colour, and depth and normals when asked.
pub(super) fn write_frame(
    frame: &trompe::Frame,
    output: &Path,
    depth: Option<&Path>,
    normals: Option<&Path>,
) -> Result<()> {
    io::write_color(output, &frame.color)?;
    if let Some(d) = depth {
        io::write_exr_depth(d, &frame.depth)?;
    }
    if let Some(n) = normals {
        io::write_exr_normals(n, &frame.normal)?;
    }
    Ok(())
}

impl RenderArgs {
    /// The method's settings the flags give.
    fn settings(&self) -> Result<MethodSettings> {
        if let Some(sp) = self.spacing.filter(|s| !(s.is_finite() && *s > 0.0)) {
            bail!("--spacing {sp}: must be a positive number of scene units");
        }
        Ok(MethodSettings {
            refraction: match self.refraction {
                RefractionArg::Exact => render::Refraction::Exact,
                RefractionArg::Wyman => render::Refraction::Wyman,
            },
            mirrors: match self.mirrors {
                MirrorsArg::Exact => render::Mirrors::Exact,
                MirrorsArg::Impostor => render::Mirrors::Impostor,
            },
            primary: match self.primary {
                PrimaryArg::Traced => render::Primary::Traced,
                PrimaryArg::Rasterized => render::Primary::Rasterized,
            },
            impostor_resolution: self.impostor_resolution,
            hybrid: trompe::hybrid::HybridSettings {
                splat: self.splat,
                spacing: self.spacing,
                ..Default::default()
            },
            octahedral_frames: self.octahedral,
            octahedral_frame_size: self.frame_size,
            ..Default::default()
        })
    }

    /// The method, refused before any work if it does not render scenes.
    fn kind(&self) -> Result<MethodKind> {
        let kind = self.method.0;
        if let Some(reason) = kind.refusal() {
            bail!("--method {kind}: {reason}");
        }
        Ok(kind)
    }

    /// Loads the scene, renders it, writes the images; prints what it wrote.
    pub(super) fn render(self, verbose: bool) -> Result<()> {
        let (kind, settings) = (self.kind()?, self.settings()?);
        // A method without a GPU path is refused before the scene loads.
        trompe_gpu::check_device(self.device.into(), kind)?;
        if let Some(frames) = self.frames {
            return self.sequence(kind, settings, frames, verbose);
        }
        // Checked before loading, then again with everything the scene reads.
        let mut plan = OutputPlan::new();
        plan.reads([&self.scene])
            .writes(&self.output, &["png", "exr"]);
        for extra in [&self.depth, &self.normals].into_iter().flatten() {
            plan.writes(extra, &["exr"]);
        }
        plan.check_overwrites()?;
        let mut timings = Timings::default();
        let mut s = timings
            .time("load scene", || Scene::load(&self.scene))
            .context("loading the scene")?;
        self.camera.apply(&mut s)?;
        check_plan(
            plan.reads(s.files.iter().cloned())
                .reads(self.camera.files()?),
        )?;
        s.warnings.iter().for_each(|w| eprintln!("warning: {w}"));
        let t = self.time.unwrap_or(s.render.time);
        let gpu = trompe_gpu::open_for(self.device.into(), kind).context("opening the GPU")?;
        let mut renderer = DeviceRenderer::new(&s, kind, settings, gpu.as_ref())?;
        if gpu.is_some() {
            crate::output::note(format_args!("rendering on {}", renderer.device_name()));
        }
        let pb = bar(kind.name(), s.camera.height as u64);
        let out = renderer.frame(t, None, pb.as_ref()).context("rendering")?;
        timings.0.extend(out.timings.0);
        if !out.report.is_empty() {
            crate::output::note(&out.report);
        }
        let frame = out.frame;
        let (depth, normals) = (self.depth.as_deref(), self.normals.as_deref());
        timings
            .time("write", || {
                write_frame(&frame, &self.output, depth, normals)
            })
            .context("writing the output")?;
        crate::output::note(format_args!("wrote {}", self.output.display()));
        print_timings(verbose, &timings);
        Ok(())
    }

    /// Renders `frames` frames into the files the output pattern names, a line a frame.
    fn sequence(
        self,
        kind: MethodKind,
        settings: MethodSettings,
        frames: u32,
        verbose: bool,
    ) -> Result<()> {
        if !(self.fps.is_finite() && self.fps > 0.0) {
            bail!(
                "--fps {}: must be a positive number of frames a second",
                self.fps
            );
        }
        if self.depth.is_some() || self.normals.is_some() {
            bail!("--depth and --normals write one frame: leave them out with --frames");
        }
        let paths: Vec<PathBuf> = (0..frames)
            .map(|i| frame_path(&self.output, i))
            .collect::<Result<_>>()?;
        let mut plan = OutputPlan::new();
        plan.creating_folders().reads([&self.scene]);
        for p in &paths {
            plan.writes(p, &["png", "exr"]);
        }
        plan.check_overwrites()?;
        let mut s = Scene::load(&self.scene).context("loading the scene")?;
        self.camera.apply(&mut s)?;
        check_plan(
            plan.reads(s.files.iter().cloned())
                .reads(self.camera.files()?),
        )?;
        s.warnings.iter().for_each(|w| eprintln!("warning: {w}"));
        if let Some(dir) = paths[0].parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir)
                .with_context(|| format!("creating the folder {}", dir.display()))?;
        }
        let t0 = self.time.unwrap_or(s.render.time);
        let gpu = trompe_gpu::open_for(self.device.into(), kind).context("opening the GPU")?;
        let mut sequence = DeviceRenderer::new(&s, kind, settings.clone(), gpu.as_ref())?;
        if gpu.is_some() {
            crate::output::note(format_args!("rendering on {}", sequence.device_name()));
        }
        let mut exact = Renderer::new(&s, MethodKind::Trace, settings)?;
        let (mut total_ms, mut total_flip) = (0.0, 0.0);
        for (i, path) in paths.iter().enumerate() {
            let t = t0 + i as f32 / self.fps;
            let start = std::time::Instant::now();
            let out = sequence
                .frame(t, None, &())
                .with_context(|| format!("rendering frame {i} (t = {t} s)"))?;
            let (frame, steps, report) = (out.frame, out.timings, out.report);
            let ms = start.elapsed().as_secs_f64() * 1e3;
            total_ms += ms;
            io::write_color(path, &frame.color)
                .with_context(|| format!("writing {}", path.display()))?;
            let mut line = format!("frame {i:>5}  t {t:>8.3} s  {ms:>8.1} ms  {report}");
            if self.compare {
                let truth = exact.frame(t, None, &())?.frame;
                let score = metrics::compare(&truth.color, &frame.color, None)?;
                total_flip += score.flip;
                line.push_str(&format!(
                    "  FLIP {:.4}  PSNR {:.1} dB",
                    score.flip, score.psnr
                ));
            }
            println!("{line}");
            print_timings(verbose, &steps);
        }
        let n = frames as f64;
        let mut summary = format!(
            "{frames} frames by {kind}: {:.1} ms a frame ({:.1} frames/s)",
            total_ms / n,
            1e3 * n / total_ms.max(f64::MIN_POSITIVE)
        );
        if self.compare {
            summary.push_str(&format!(", mean FLIP {:.4} against trace", total_flip / n));
        }
        println!("{summary}");
        crate::output::note(format_args!(
            "wrote {} … {}",
            paths[0].display(),
            paths[paths.len() - 1].display()
        ));
        Ok(())
    }
}

/// The file of frame `i` that `pattern` names: its one `%d` or `%0Nd` replaced by `i`
/// (zero-padded to N digits).
fn frame_path(pattern: &Path, i: u32) -> Result<PathBuf> {
    let text = pattern.to_string_lossy();
    let Some(start) = text.find('%') else {
        bail!(
            "-o {}: with --frames it needs a %04d (or %d) where the frame number goes",
            pattern.display()
        );
    };
    let rest = &text[start + 1..];
    let digits: String = rest.chars().take_while(char::is_ascii_digit).collect();
    let after = rest[digits.len()..].strip_prefix('d');
    if after.is_none_or(|a| a.contains('%')) {
        bail!(
            "-o {}: the pattern takes one %d or %0Nd (such as %04d)",
            pattern.display()
        );
    }
    let width: usize = digits.parse().unwrap_or(0);
    if width > 10 {
        bail!("-o {}: at most 10 digits a frame number", pattern.display());
    }
    let number = format!("{i:0width$}");
    let end = start + 1 + digits.len() + 1;
    Ok(PathBuf::from(format!(
        "{}{number}{}",
        &text[..start],
        &text[end..]
    )))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frame_patterns() {
        let p = |s: &str, i| frame_path(Path::new(s), i).map(|p| p.display().to_string());
        assert_eq!(p("out/frame_%04d.png", 7).unwrap(), "out/frame_0007.png");
        assert_eq!(p("f%d.exr", 12).unwrap(), "f12.exr");
        assert!(p("frame.png", 0).is_err());
        assert!(p("a%04d_%d.png", 0).is_err());
        assert!(p("a%s.png", 0).is_err());
    }
}
