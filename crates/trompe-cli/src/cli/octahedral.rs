//! `trompe impostor bake --octahedral` and its batches, `impostor export` and
//! `impostor merge-manifests`: octahedral impostors for engines on the command line — parse,
//! call `trompe::octahedral`, print its report.

use super::impostor::{BakeArgs, GeometryArg};
use super::{OutputPlan, check_plan, has_extension, with_spinner};
use anyhow::{Context, Result};
use indicatif::{ProgressBar, ProgressStyle};
use std::path::PathBuf;

/// `--shard`: `K/N`, or read from a job scheduler's variables (`auto`; `auto/N` with the count,
/// which Kubernetes does not give).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ShardArg {
    /// Shard K of N.
    Given(trompe::octahedral::batch::Shard),
    /// From Slurm's or Kubernetes' variables, with the count if given.
    Auto(Option<u32>),
}

impl std::str::FromStr for ShardArg {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s.trim().strip_prefix("auto") {
            Some("") => Ok(ShardArg::Auto(None)),
            Some(rest) => match rest.strip_prefix('/').map(str::parse::<u32>) {
                Some(Ok(n)) if n > 0 => Ok(ShardArg::Auto(Some(n))),
                _ => Err(format!("{s:?}: expected auto or auto/N with N ≥ 1")),
            },
            None => s.parse().map(ShardArg::Given),
        }
    }
}

impl ShardArg {
    /// The shard, reading the scheduler's variables for `auto`.
    fn resolve(self) -> Result<trompe::octahedral::batch::Shard> {
        match self {
            ShardArg::Given(s) => Ok(s),
            ShardArg::Auto(count) => Ok(trompe::octahedral::batch::Shard::from_scheduler(
                |name| std::env::var(name).ok(),
                count,
            )?),
        }
    }
}

/// `trompe impostor export`.
#[derive(clap::Args, Debug)]
pub struct ExportArgs {
    /// The impostor's sidecar (NAME.json, from `impostor bake`, octahedral or not).
    input: PathBuf,
    /// The .glb to write.
    #[arg(short, long)]
    output: PathBuf,
    /// For an impostor's surface: compressed (16-bit positions, 8-bit normals, meshopt codecs:
    /// KHR_mesh_quantization and EXT_meshopt_compression) or float (plain glTF).
    #[arg(long, value_enum, default_value_t = GeometryArg::Compressed)]
    geometry: GeometryArg,
}

impl ExportArgs {
    pub(super) fn export(self) -> Result<()> {
        use trompe::sidecar::SidecarKind;
        let octahedral = SidecarKind::of(&self.input)? == SidecarKind::Octahedral;
        let mut plan = OutputPlan::new();
        plan.creating_folders().writes(&self.output, &["glb"]);
        if octahedral {
            plan.reads(trompe::octahedral::file::files(&self.input));
        } else {
            plan.reads([self.input.clone(), self.input.with_extension("exr")]);
        }
        plan.check_overwrites()?;
        plan.make_folders()
            .context("creating the output's folder")?;
        let exported = if octahedral {
            trompe::octahedral::gltf::export(&self.input, &self.output).map_err(anyhow::Error::from)
        } else {
            trompe::impostor::gltf::export(&self.input, &self.output, self.geometry.into())
                .map_err(anyhow::Error::from)
        };
        exported.with_context(|| format!("exporting {}", self.input.display()))?;
        crate::output::note(format_args!("wrote {}", self.output.display()));
        Ok(())
    }
}

/// `trompe impostor merge-manifests`.
#[derive(clap::Args, Debug)]
pub struct MergeArgs {
    /// The shards' manifests (manifest-K-of-N.json).
    #[arg(required = true)]
    manifests: Vec<PathBuf>,
    /// The joined manifest to write.
    #[arg(short, long)]
    output: PathBuf,
}

impl MergeArgs {
    pub(super) fn merge(self) -> Result<()> {
        let mut plan = OutputPlan::new();
        plan.reads(self.manifests.iter())
            .writes(&self.output, &["json"]);
        plan.check_overwrites()?;
        let manifests = self
            .manifests
            .iter()
            .map(|p| {
                let text = std::fs::read_to_string(p)
                    .with_context(|| format!("reading {}", p.display()))?;
                serde_json::from_str(&text)
                    .with_context(|| format!("{}: not a batch manifest", p.display()))
            })
            .collect::<Result<Vec<trompe::octahedral::batch::Manifest>>>()?;
        let merged = trompe::octahedral::batch::merge(&manifests)?;
        let text = serde_json::to_string_pretty(&merged)?;
        trompe::files::write_atomically(&self.output, text.as_bytes())
            .with_context(|| format!("writing {}", self.output.display()))?;
        let failed = merged.entries.iter().filter(|e| e.error.is_some()).count();
        println!(
            "{} files from {} shards, {failed} failed; wrote {}",
            merged.entries.len(),
            merged.shards.len(),
            self.output.display()
        );
        Ok(())
    }
}

impl BakeArgs {
    /// The octahedral settings these arguments ask for.
    pub(super) fn octahedral_settings(&self, n: u32) -> Result<trompe::octahedral::BakeSettings> {
        use trompe::octahedral::{BakeSettings, Coverage, Grid};
        if self.layers != trompe::impostor::Layers::ONE {
            anyhow::bail!(
                "--layers {}: an octahedral atlas holds one layer a frame; peeling is for depth-image impostors",
                self.layers
            );
        }
        let frame_size = self.resolution / n;
        if frame_size < 8 {
            anyhow::bail!(
                "--resolution {} / --octahedral {n} leaves {frame_size} texels a frame; give at least 8",
                self.resolution
            );
        }
        let grid = Grid {
            n,
            coverage: if self.hemi {
                Coverage::Hemisphere
            } else {
                Coverage::Sphere
            },
        };
        Ok(
            BakeSettings::new(grid, frame_size).with_projection(match self.perspective {
                Some(distance) => trompe::octahedral::FrameProjection::Pinhole { distance },
                None => trompe::octahedral::FrameProjection::Orthographic,
            }),
        )
    }

    /// Whether this is a batch: several inputs, a folder or a list of them, a shard, or an
    /// output that is neither a .json nor a .glb file.
    pub(super) fn is_batch(&self) -> bool {
        self.inputs.len() > 1
            || self.inputs.iter().any(|p| p.is_dir())
            || self.inputs_from.is_some()
            || !(has_extension(&self.output, "json") || has_extension(&self.output, "glb"))
            || self.shard.is_some()
    }

    /// How the .glb holds its textures.
    fn texture_format(&self) -> trompe::octahedral::gltf::TextureFormat {
        match self.ktx2 {
            true => trompe::octahedral::gltf::TextureFormat::Ktx2,
            false => trompe::octahedral::gltf::TextureFormat::Png,
        }
    }

    /// The float maps these arguments ask for.
    fn floats(&self) -> trompe::octahedral::file::FloatMaps {
        match self.exr {
            true => trompe::octahedral::file::FloatMaps::OpenExr,
            false => trompe::octahedral::file::FloatMaps::Omitted,
        }
    }

    /// A batch of octahedral bakes into the folder -o names: a shard of the sorted inputs,
    /// each file baked (or, with --skip-existing, kept as an earlier run finished it) or skipped
    /// with its error, a journal then a manifest; fails at the end if any failed.
    /// Bakes this shard's inputs; fails (exit code 1) where any input could not be baked, after
    /// printing the report.
    pub(super) fn bake_batch(&self, n: u32) -> Result<std::process::ExitCode> {
        if has_extension(&self.output, "glb") || has_extension(&self.output, "json") {
            anyhow::bail!(
                "-o {}: a batch writes into a folder (NAME.json and its maps for each input, \
                 NAME.glb beside them with --glb): give -o FOLDER/",
                self.output.display()
            );
        }
        if self.ktx2 && !self.glb {
            anyhow::bail!("--ktx2 sets the .glb's textures: add --glb");
        }
        use trompe::octahedral::batch::{
            BatchSettings, Outcome, bake_all, gather, journal_path, listed, manifest_path, outputs,
            shard_inputs,
        };
        let settings = BatchSettings {
            bake: self.octahedral_settings(n)?,
            glb: self.glb.then_some(self.texture_format()),
            floats: self.floats(),
            skip_existing: self.skip_existing,
        };
        let shard = match self.shard {
            None => trompe::octahedral::batch::Shard::ALL,
            Some(s) => s.resolve()?,
        };
        let list = match &self.inputs_from {
            None => Vec::new(),
            Some(p) if p.as_os_str() == "-" => {
                let mut text = String::new();
                std::io::Read::read_to_string(&mut std::io::stdin(), &mut text)
                    .context("reading the list of inputs from standard input")?;
                listed(&text)
            }
            Some(p) => listed(
                &std::fs::read_to_string(p)
                    .with_context(|| format!("reading the list of inputs {}", p.display()))?,
            ),
        };
        let all = gather(&self.inputs, &list)?;
        if all.is_empty() {
            anyhow::bail!(
                "no meshes to bake: the inputs name none (a folder's walk takes .{})",
                trompe::octahedral::batch::MESH_EXTENSIONS.join(", .")
            );
        }
        let mine = shard_inputs(&all, shard);
        let manifest = manifest_path(&self.output, shard);
        let journal = journal_path(&self.output, shard);
        let mut plan = OutputPlan::new();
        plan.creating_folders()
            .reads(all.iter().map(|i| i.path.clone()));
        plan.reads(
            self.inputs_from
                .iter()
                .filter(|p| p.as_os_str() != "-")
                .cloned(),
        );
        for o in outputs(&mine, &self.output, self.glb) {
            plan.writes(o, &["json", "png", "exr", "glb"]);
        }
        plan.writes(&manifest, &["json"]);
        plan.writes(&journal, &["jsonl"]);
        plan.check_overwrites()?;
        for input in &mine {
            trompe::octahedral::file::check_replaceable(
                &input.sidecar(&self.output),
                settings.floats,
            )?;
        }
        std::fs::create_dir_all(&self.output)
            .with_context(|| format!("creating {}", self.output.display()))?;
        let pb = match crate::output::quiet() {
            true => ProgressBar::hidden(),
            false => ProgressBar::new(mine.len() as u64),
        };
        pb.set_style(
            ProgressStyle::with_template("{msg:>28} [{bar:30}] {pos}/{len} {elapsed}")
                .unwrap_or_else(|_| ProgressStyle::default_bar())
                .progress_chars("=> "),
        );
        pb.set_message(format!("shard {shard}"));
        let mut kept = 0;
        let manifest_written =
            bake_all(&mine, &self.output, settings, shard, &mut |e, outcome| {
                pb.suspend(|| match (outcome, &e.error) {
                    (Outcome::Failed, Some(err)) => {
                        eprintln!("skipped {}: {err}", e.input.display())
                    }
                    (Outcome::UpToDate, _) => {
                        kept += 1;
                        crate::output::note(format_args!("up to date {}", e.input.display()))
                    }
                    _ => crate::output::note(format_args!(
                        "baked {} ({} triangles) in {:.2} s",
                        e.input.display(),
                        e.triangles.unwrap_or(0),
                        e.seconds
                    )),
                });
                pb.inc(1);
            })?;
        pb.finish_and_clear();
        let entries = &manifest_written.entries;
        let failed = entries.iter().filter(|e| e.error.is_some()).count();
        let text = format!(
            "shard {shard}: {} of {} files baked ({kept} already up to date); wrote {}",
            entries.len() - failed,
            entries.len(),
            manifest.display()
        );
        let result = serde_json::json!({
            "shard": shard.to_string(),
            "files": entries.len(),
            "baked": entries.len() - failed,
            "up_to_date": kept,
            "failed": failed,
            "manifest": manifest,
            "entries": entries,
        });
        crate::output::report("impostor bake", text, &result)?;
        if failed > 0 {
            // The failures are in the report (and named above in text): exit 1 without a
            // second document.
            if !crate::output::json() {
                eprintln!(
                    "error: {failed} of {} files could not be baked (named above)",
                    entries.len()
                );
            }
            return Ok(std::process::ExitCode::from(1));
        }
        Ok(std::process::ExitCode::SUCCESS)
    }

    pub(super) fn bake_octahedral(
        &self,
        n: u32,
    ) -> Result<trompe::octahedral::file::OctahedralReport> {
        use trompe::octahedral::{bake, file};
        let settings = self.octahedral_settings(n)?;
        let input = self.input()?;
        let files = file::files(&self.output);
        // -o NAME.glb: that one self-contained file, nothing beside it.
        let alone = has_extension(&self.output, "glb");
        if self.ktx2 && !(alone || self.glb) {
            anyhow::bail!(
                "--ktx2 sets the .glb's textures: give -o NAME.glb, or add --glb beside -o NAME.json"
            );
        }
        if alone && (self.glb || self.exr) {
            anyhow::bail!(
                "-o {}: a .glb output is the whole bake; --glb and --exr add files beside a \
                 NAME.json output",
                self.output.display()
            );
        }
        let glb = self.output.with_extension("glb");
        let mut plan = OutputPlan::new();
        plan.creating_folders().reads([input]);
        if alone {
            plan.writes(&glb, &["glb"]);
        } else {
            plan.writes(&files[0], &["json"])
                .writes(&files[1], &["png"])
                .writes(&files[2], &["png"])
                .writes(&files[3], &["png"]);
            if self.exr {
                plan.writes(&files[4], &["exr"]).writes(&files[5], &["exr"]);
            }
            if self.glb {
                plan.writes(&glb, &["glb"]);
            }
        }
        plan.check_overwrites()?;
        if !alone {
            file::check_replaceable(&self.output, self.floats())?;
        }
        let loaded = trompe::geom::io::load(input)
            .with_context(|| format!("loading {}", input.display()))?;
        check_plan(plan.reads(loaded.files.iter().cloned()))?;
        plan.make_folders()
            .context("creating the output's folder")?;
        let start = std::time::Instant::now();
        let atlas = with_spinner("baking the octahedral atlas", || {
            bake(
                &loaded.mesh,
                &trompe::scene::Surface::Diffuse(None),
                settings,
            )
        })?;
        let bake_time = start.elapsed();
        let format = self.texture_format();
        // KTX2 encoding takes seconds at 2048²: said while it runs.
        let save_glb = || {
            with_spinner("encoding the .glb's textures", || {
                trompe::octahedral::gltf::save(&atlas, &glb, format)
            })
            .context("writing the glTF")
        };
        if alone {
            let sidecar = save_glb()?;
            return Ok(file::OctahedralReport::new(
                &atlas,
                sidecar,
                vec![glb],
                bake_time,
            ));
        }
        let sidecar =
            file::save(&atlas, &self.output, self.floats()).context("writing the atlas")?;
        let mut written = file::written(&self.output, &sidecar);
        if self.glb {
            save_glb()?;
            written.push(glb);
        }
        Ok(file::OctahedralReport::new(
            &atlas, sidecar, written, bake_time,
        ))
    }
}
