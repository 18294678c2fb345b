//! `trompe relief SCENE`: a walk through relief impostors (paper 3) on the command line —
//! parse, call `trompe::relief::walk`, write its frames and CSV, print its report.

use super::{bar, check_plan};
use anyhow::{Context, Result};
use std::path::PathBuf;
use trompe::files::{FolderKind, OutputPlan, StagedFolder};
use trompe::frame::io;
use trompe::scene::Scene;

/// `trompe relief`.
#[derive(clap::Args, Debug)]
pub struct ReliefArgs {
    /// Scene file (its camera path, or an orbit around its `look_at` when it has none).
    scene: PathBuf,
    /// Output folder: frame_NNNN.png for every frame, walk.csv, and with --truth the true
    /// renders truth_NNNN.png.
    #[arg(short, long)]
    output: PathBuf,
    /// Frames along the path.
    #[arg(long, default_value_t = 120, value_parser = clap::value_parser!(u32).range(1..=100_000))]
    frames: u32,
    /// Relief resolution, texels a side.
    #[arg(long, default_value_t = 256, value_parser = clap::value_parser!(u32).range(4..=4096))]
    resolution: u32,
    /// Objects drawn as relief impostors, by scene name (repeatable; default: every object).
    #[arg(long = "object", value_name = "NAME")]
    objects: Vec<String>,
    /// Interpolated share (interpolated over direct texels) past which an impostor is
    /// obsolete; the critical-point heuristic judges it each frame.
    #[arg(long, default_value_t = trompe::relief::validity::RATIO_THRESHOLD)]
    threshold: f64,
    /// Store displacements as f32 instead of the paper's eight bits.
    #[arg(long)]
    f32_depth: bool,
    /// Deterministic mode: use each new impostor exactly this many frames after its request.
    #[arg(long, value_name = "FRAMES", value_parser = clap::value_parser!(u32).range(0..=1000))]
    deterministic: Option<u32>,
    /// Camera-path prediction: make new impostors for where the eye will be this many frames
    /// ahead.
    #[arg(long, default_value_t = 2, value_parser = clap::value_parser!(u32).range(0..=1000))]
    predict: u32,
    /// Skip the true render and the scores (the walk then runs at its own pace).
    #[arg(long)]
    no_score: bool,
    /// Also write each frame's true render.
    #[arg(long)]
    truth: bool,
}

impl ReliefArgs {
    pub(super) fn walk(&self) -> Result<()> {
        use trompe::relief::{DepthEncoding, PipelineSettings, WalkSettings, walk};
        let mut settings = WalkSettings {
            frames: self.frames,
            pipeline: PipelineSettings {
                resolution: self.resolution,
                first_resolution: Some((self.resolution / 4).max(4)),
                encoding: if self.f32_depth {
                    DepthEncoding::F32
                } else {
                    DepthEncoding::U8
                },
                threshold: self.threshold,
                deterministic: self.deterministic,
                predict: self.predict,
                ..Default::default()
            },
            objects: Vec::new(),
            score: !self.no_score,
        };
        settings.pipeline.validate()?;
        let out = &self.output;
        let scene = Scene::load(&self.scene).context("loading the scene")?;
        for w in &scene.warnings {
            eprintln!("warning: {w}");
        }
        for name in &self.objects {
            settings.objects.push(scene.object_named(name)?);
        }
        let mut plan = OutputPlan::new();
        plan.reads(scene.files.iter().cloned())
            .writes_folder(out, FolderKind::ReliefWalk)
            .writes(out.join("walk.csv"), &["csv"])
            .creating_folders();
        check_plan(&plan)?;
        // The frames and the table are one result: written aside, published whole at the end.
        let staged = StagedFolder::begin(out, FolderKind::ReliefWalk)?;
        let dir = staged.path();
        let progress = bar("walking", self.frames as u64);
        let write = |path: PathBuf, image: &trompe::Image<trompe::Rgba>| {
            io::write_png(&path, image).map_err(trompe::relief::ReliefError::Frame)
        };
        let mut sink = |i: usize, frame: &trompe::Frame, truth: Option<&trompe::Frame>| {
            write(dir.join(format!("frame_{i:04}.png")), &frame.color)?;
            if let (true, Some(t)) = (self.truth, truth) {
                write(dir.join(format!("truth_{i:04}.png")), &t.color)?;
            }
            Ok(())
        };
        let report = walk(&scene, &settings, progress.as_ref(), &mut sink)
            .with_context(|| format!("walking {}", self.scene.display()))?;
        let csv = dir.join("walk.csv");
        trompe::files::write_atomically(&csv, report.csv().as_bytes())
            .with_context(|| format!("writing {}", csv.display()))?;
        staged.publish()?;
        println!("{report}");
        println!(
            "wrote {} frames and walk.csv to {}",
            self.frames,
            out.display()
        );
        Ok(())
    }
}
