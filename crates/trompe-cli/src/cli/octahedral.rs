//! `trompe impostor bake --octahedral` and its batches, `impostor export` and
//! `impostor merge-manifests`: octahedral impostors for engines on the command line — parse,
//! call `trompe::octahedral`, print its report.

use super::{BakeArgs, OutputPlan, check_plan, has_extension, with_spinner};
use anyhow::{Context, Result};
use indicatif::{ProgressBar, ProgressStyle};
use std::path::PathBuf;

/// `trompe impostor export`.
#[derive(clap::Args, Debug)]
pub struct ExportArgs {
    /// The impostor's sidecar (NAME.json, from `impostor bake`, octahedral or not).
    input: PathBuf,
    /// The .glb to write.
    #[arg(short, long)]
    output: PathBuf,
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
            trompe::impostor::gltf::export(&self.input, &self.output).map_err(anyhow::Error::from)
        };
        exported.with_context(|| format!("exporting {}", self.input.display()))?;
        eprintln!("wrote {}", self.output.display());
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

    /// Whether this is a batch: several inputs, or an output that is not a .json file.
    pub(super) fn is_batch(&self) -> bool {
        self.inputs.len() > 1 || !has_extension(&self.output, "json") || self.shard.is_some()
    }

    /// A batch of octahedral bakes into the folder -o names: a shard of the sorted inputs,
    /// each file baked or skipped with its error, a manifest; fails at the end if any failed.
    pub(super) fn bake_batch(&self, n: u32) -> Result<()> {
        use trompe::octahedral::batch::{Shard, bake_all, outputs, shard_inputs};
        let settings = self.octahedral_settings(n)?;
        let shard = self.shard.unwrap_or(Shard { index: 1, count: 1 });
        let mine = shard_inputs(&self.inputs, shard)?;
        let manifest_path = self
            .output
            .join(format!("manifest-{}-of-{}.json", shard.index, shard.count));
        let mut plan = OutputPlan::new();
        plan.creating_folders().reads(self.inputs.iter());
        for o in outputs(&mine, &self.output, self.glb) {
            plan.writes(o, &["json", "png", "exr", "glb"]);
        }
        plan.writes(&manifest_path, &["json"]);
        plan.check_overwrites()?;
        for input in &mine {
            trompe::octahedral::file::check_replaceable(&trompe::octahedral::batch::output_for(
                input,
                &self.output,
            ))?;
        }
        std::fs::create_dir_all(&self.output)
            .with_context(|| format!("creating {}", self.output.display()))?;
        let pb = ProgressBar::new(mine.len() as u64);
        pb.set_style(
            ProgressStyle::with_template("{msg:>28} [{bar:30}] {pos}/{len} {elapsed}")
                .unwrap_or_else(|_| ProgressStyle::default_bar())
                .progress_chars("=> "),
        );
        pb.set_message(format!("shard {}/{}", shard.index, shard.count));
        let manifest = bake_all(
            &mine,
            &self.output,
            settings,
            self.glb,
            shard,
            &mut |e, secs| {
                pb.suspend(|| match (&e.error, e.triangles) {
                    (Some(err), _) => eprintln!("skipped {}: {err}", e.input.display()),
                    (None, t) => eprintln!(
                        "baked {} ({} triangles) in {secs:.2} s",
                        e.input.display(),
                        t.unwrap_or(0)
                    ),
                });
                pb.inc(1);
            },
        );
        pb.finish_and_clear();
        let text = serde_json::to_string_pretty(&manifest)?;
        trompe::files::write_atomically(&manifest_path, text.as_bytes())
            .with_context(|| format!("writing {}", manifest_path.display()))?;
        let failed = manifest
            .entries
            .iter()
            .filter(|e| e.error.is_some())
            .count();
        println!(
            "shard {}/{}: {} of {} files baked; wrote {}",
            shard.index,
            shard.count,
            manifest.entries.len() - failed,
            manifest.entries.len(),
            manifest_path.display()
        );
        if failed > 0 {
            anyhow::bail!(
                "{failed} of {} files could not be baked (named above)",
                manifest.entries.len()
            );
        }
        Ok(())
    }

    pub(super) fn bake_octahedral(
        &self,
        n: u32,
    ) -> Result<trompe::octahedral::file::OctahedralReport> {
        use trompe::octahedral::{bake, file};
        let settings = self.octahedral_settings(n)?;
        let input = self.input()?;
        let files = file::files(&self.output);
        let glb = self.output.with_extension("glb");
        let mut plan = OutputPlan::new();
        plan.creating_folders()
            .reads([input])
            .writes(&files[0], &["json"])
            .writes(&files[1], &["png"])
            .writes(&files[2], &["exr"])
            .writes(&files[3], &["exr"])
            .writes(&files[4], &["png"]);
        if self.glb {
            plan.writes(&glb, &["glb"]);
        }
        plan.check_overwrites()?;
        file::check_replaceable(&self.output)?;
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
        let sidecar = file::save(&atlas, &self.output).context("writing the atlas")?;
        if self.glb {
            trompe::octahedral::gltf::export(&self.output, &glb).context("writing the glTF")?;
            eprintln!("wrote {}", glb.display());
        }
        Ok(file::OctahedralReport::new(
            &atlas, sidecar, files, bake_time,
        ))
    }
}
