//! `trompe impostor …`: bake, check, export and merge impostors — the arguments and the glue
//! over [`trompe::impostor`] and [`trompe::eval::check`]. No algorithm lives here.

use super::{
    MAX_IMPOSTOR_SIDE, check_plan, octahedral, parse_strength, print_timings, with_spinner,
};
use anyhow::{Context, Result, bail};
use clap::{Subcommand, ValueEnum};
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use trompe::eval::check::{BakedCheckSettings, CheckSettings, check_baked, check_built};
use trompe::files::OutputPlan;
use trompe::frame::io;
use trompe::impostor::{BakeSettings, CameraChoice, Subject, ViewCamera, bake};

/// The most rays `impostor check` fires from one source (bounds its memory: 32 bytes a ray).
const MAX_CHECK_RAYS: i64 = 10_000_000;

/// `trompe impostor …`.
#[derive(Subcommand, Debug)]
pub enum ImpostorCommand {
    /// Build an impostor of a mesh (or a maze, with --camera graph) and save it: a JSON
    /// sidecar, the EXR of its maps beside it, and a PNG preview of its colour.
    Bake(BakeArgs),
    /// Fire rays at an object and compare every impostor answer with the exact BVH.
    Check(CheckArgs),
    /// Join the manifests of a sharded octahedral batch into one.
    MergeManifests(octahedral::MergeArgs),
    /// Write a baked impostor as a glTF 2.0 binary that engines load without trompe: an
    /// octahedral atlas as a card with the atlas and its layout; any other as its surface, a
    /// textured mesh, with its camera.
    Export(octahedral::ExportArgs),
}

impl ImpostorCommand {
    /// Runs the subcommand and prints its report.
    pub(super) fn run(self, verbose: bool) -> Result<ExitCode> {
        match self {
            ImpostorCommand::Check(args) => {
                let output = args.output.clone();
                let misses = args.misses.clone();
                let report = with_spinner("checking", || args.check())?;
                if let Some(o) = &output {
                    trompe::impostor::file::save(&report.impostor, o)
                        .context("saving the impostor")?;
                    crate::output::note(format_args!("wrote {}", o.display()));
                }
                if let Some(m) = &misses {
                    let picture = trompe::eval::misses::side_by_side(&report.misses)?;
                    io::write_png(m, &picture)
                        .with_context(|| format!("writing {}", m.display()))?;
                    crate::output::note(format_args!("wrote {}", m.display()));
                }
                crate::output::report("impostor check", &report, &report)?;
                print_timings(verbose, &report.timings);
            }
            ImpostorCommand::MergeManifests(args) => args.merge()?,
            ImpostorCommand::Export(args) => args.export()?,
            ImpostorCommand::Bake(args) => match args.octahedral {
                Some(n) if args.is_batch() => return args.bake_batch(n),
                Some(n) => {
                    let report = args.bake_octahedral(n)?;
                    crate::output::report("impostor bake", &report, &report)?;
                }
                None => {
                    let report = args.bake()?;
                    crate::output::report("impostor bake", &report, &report)?;
                    print_timings(verbose, &report.timings);
                }
            },
        }
        Ok(ExitCode::SUCCESS)
    }
}

/// `trompe impostor check`.
#[derive(clap::Args, Debug)]
pub struct CheckArgs {
    /// The object (.obj, .ply, .gltf, .glb), in its own coordinates; or a floor plan (.maze)
    /// for --camera graph, with the reflector standing in its first corridor.
    mesh: PathBuf,
    /// Impostor camera.
    #[arg(long, value_enum, default_value_t = CameraArg::Spoc)]
    camera: CameraArg,
    /// SPOC strength k (default: chosen per object on rays a second viewer sees in the mirror:
    /// the rule k = 2Δ/z_O from the reflector's region, a weaker push, or the pinhole).
    #[arg(long, value_parser = parse_strength)]
    k: Option<f64>,
    /// Impostor resolution (square).
    #[arg(long, default_value_t = 512,
          value_parser = clap::value_parser!(u32).range(1..=MAX_IMPOSTOR_SIDE))]
    resolution: u32,
    /// The reflector whose reflected rays are fired (default: a built-in sphere), scaled to
    /// 0.8 of the object's largest extent.
    #[arg(long)]
    reflector: Option<PathBuf>,
    /// Distance between the object's and the reflector's centres, in the object's largest
    /// extents.
    #[arg(long, default_value_t = 1.4)]
    distance: f32,
    /// Resolution of the view of the reflector that spawns the rays.
    #[arg(long, default_value_t = 1024)]
    view: u32,
    /// Also fire this many rays from a sphere around the object, aimed at it.
    #[arg(long, default_value_t = 0,
          value_parser = clap::value_parser!(u32).range(0..=MAX_CHECK_RAYS))]
    sphere_rays: u32,
    /// Save the impostor (JSON sidecar; the EXR goes beside it).
    #[arg(short, long)]
    output: Option<PathBuf>,
    /// Check this baked impostor (its JSON sidecar, from `impostor bake`) rather than
    /// building one. MESH is then the object it was baked from, in its own coordinates,
    /// and the rays come from around the impostor's viewpoint (`--region`) — for a graph
    /// camera, from the reflector in the maze's first corridor.
    #[arg(long, conflicts_with_all = ["camera", "k", "resolution", "output", "distance"])]
    impostor: Option<PathBuf>,
    /// With --impostor: radius of the region around its viewpoint the rays come from, in
    /// bounding radii of the object (`bake` chooses the SPOC strength for 1).
    #[arg(long, default_value_t = 1.0, requires = "impostor")]
    region: f32,
    /// With --impostor: how many rays come from that region.
    #[arg(long, default_value_t = 20_000, requires = "impostor",
          value_parser = clap::value_parser!(u32).range(1..=MAX_CHECK_RAYS))]
    rays: u32,
    /// Depth layers: a count from 1 to 8, or auto (added while a new layer holds more than
    /// 1 % of the first layer's texels: the configuration that holds paper 1's figures). With
    /// more than one, the impostor with 1, 2, 4 and auto layers is checked beside it on the
    /// same rays, and the pinhole beside a SPOC is peeled alike.
    #[arg(long, default_value = "auto", conflicts_with = "impostor")]
    layers: trompe::impostor::Layers,
    /// Draw where the impostor disagrees with the exact BVH into this PNG: its colour image
    /// dimmed, each disagreeing ray marked at its point (red: the impostor misses; orange: both
    /// hit, too far apart; blue: only the impostor hits), the pinhole beside a SPOC to its right.
    #[arg(long)]
    misses: Option<PathBuf>,
}

/// `trompe impostor bake`.
#[derive(clap::Args, Debug)]
pub struct BakeArgs {
    /// The object (.obj, .ply, .gltf, .glb), in its own coordinates; or a floor plan
    /// (.maze) for --camera graph. With --octahedral, any number of meshes and folders (walked
    /// for the meshes they hold): a batch into the folder -o names, the input folders mirrored.
    #[arg(required_unless_present = "inputs_from")]
    pub(super) inputs: Vec<PathBuf>,
    /// With --octahedral: also bake the meshes this file lists, one path a line ("-": standard
    /// input; blank lines and lines starting with # skipped).
    #[arg(long)]
    pub(super) inputs_from: Option<PathBuf>,
    /// With --octahedral and a batch: skip each input an earlier run into the same folder
    /// finished — its input, its settings and its outputs still as its manifest or journal
    /// recorded them — and bake the rest.
    #[arg(long)]
    pub(super) skip_existing: bool,
    /// Impostor camera.
    #[arg(long, value_enum, default_value_t = CameraArg::Spoc)]
    pub(super) camera: CameraArg,
    /// Impostor resolution (square).
    #[arg(long, default_value_t = 512,
          value_parser = clap::value_parser!(u32).range(1..=MAX_IMPOSTOR_SIDE))]
    pub(super) resolution: u32,
    /// Direction from the object's centre toward the camera, "x,y,z".
    #[arg(long, default_value = "0,0.3,1", value_parser = parse_vec3)]
    pub(super) from: glam::Vec3,
    /// Camera distance from the object's centre, in bounding-sphere radii.
    #[arg(long, default_value_t = 3.0)]
    pub(super) distance: f32,
    /// SPOC strength k (default: chosen per object on rays from within one radius of the
    /// viewpoint: the rule k = 2Δ/z_O with Δ that radius, a weaker push, or the pinhole).
    #[arg(long, value_parser = parse_strength)]
    pub(super) k: Option<f64>,
    /// The sidecar to write (NAME.json; NAME.exr and NAME.png go beside it).
    #[arg(short, long)]
    pub(super) output: PathBuf,
    /// Bake an octahedral atlas of N × N frames instead (--resolution is the atlas side): with
    /// -o NAME.glb one self-contained glTF file; with -o NAME.json the layout, and NAME.png,
    /// NAME-normal-depth.png and NAME-orm.png beside it.
    #[arg(long, value_parser = clap::value_parser!(u32).range(2..=64))]
    pub(super) octahedral: Option<u32>,
    /// With --octahedral: the upper hemisphere only (hemi-octahedral).
    #[arg(long)]
    pub(super) hemi: bool,
    /// With --octahedral: pinhole frames, the eye this many bounding radii from the centre
    /// (more than 1), instead of orthographic ones.
    #[arg(long)]
    pub(super) perspective: Option<f32>,
    /// Also write NAME.glb, a glTF 2.0 file engines load: for an octahedral atlas, a card with
    /// the atlas and its layout; for any other impostor, its surface as a textured mesh, with its
    /// camera.
    #[arg(long)]
    pub(super) glb: bool,
    /// With --octahedral: the .glb's textures as KTX2 (Basis Universal UASTC, Zstandard
    /// supercompression, glTF's KHR_texture_basisu) with a mip chain made frame by frame,
    /// instead of PNG.
    #[arg(long)]
    pub(super) ktx2: bool,
    /// Without --octahedral: how the .glb stores the surface — compressed (16-bit positions,
    /// 8-bit normals, meshopt codecs: glTF's KHR_mesh_quantization and EXT_meshopt_compression,
    /// which three.js, Babylon.js, glTFast and Godot read) or float (plain glTF every reader
    /// loads).
    #[arg(long, value_enum, default_value_t = GeometryArg::Compressed)]
    pub(super) geometry: GeometryArg,
    /// With --octahedral and -o NAME.json or a batch: also write the normal and depth maps as
    /// 32-bit float OpenEXR files (NAME-normal.exr, NAME-depth.exr), for pipelines that want
    /// them unquantized.
    #[arg(long)]
    pub(super) exr: bool,
    /// With --octahedral and a batch: bake only shard K of N of the sorted inputs ("K/N",
    /// 1-based); "auto" reads it from a Slurm array job's variables, "auto/N" from a Kubernetes
    /// Indexed Job's JOB_COMPLETION_INDEX (0-based) with N completions.
    #[arg(long)]
    pub(super) shard: Option<octahedral::ShardArg>,
    /// Depth layers peeled through the camera: a count from 1 to 8 (peeling stops early at a
    /// layer that would hold nothing), or auto (added while a new layer holds more than 1 % of
    /// the first layer's texels).
    #[arg(long, default_value = "1")]
    pub(super) layers: trompe::impostor::Layers,
}

/// `--geometry` of `impostor bake` and `impostor export`.
#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum GeometryArg {
    /// Quantized and meshopt-compressed.
    Compressed,
    /// 32-bit floats.
    Float,
}

impl From<GeometryArg> for trompe::impostor::gltf::GeometryEncoding {
    fn from(arg: GeometryArg) -> Self {
        match arg {
            GeometryArg::Compressed => Self::Compressed,
            GeometryArg::Float => Self::Float,
        }
    }
}

/// `--camera` of `impostor`.
#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum CameraArg {
    /// Planar pinhole depth image.
    Pinhole,
    /// Parallel projection.
    Orthographic,
    /// Single-pole occlusion camera.
    Spoc,
    /// Graph camera following a maze's corridors (input: a .maze floor plan).
    Graph,
}

impl CameraArg {
    /// The library's name for this camera, with the SPOC strength when given.
    fn choice(self, k: Option<f64>) -> CameraChoice {
        match self {
            CameraArg::Pinhole => CameraChoice::Placed(ViewCamera::Pinhole),
            CameraArg::Orthographic => CameraChoice::Placed(ViewCamera::Orthographic),
            CameraArg::Spoc => CameraChoice::Placed(ViewCamera::Spoc(k)),
            CameraArg::Graph => CameraChoice::Graph,
        }
    }
}

/// Parses "x,y,z".
fn parse_vec3(text: &str) -> Result<glam::Vec3, String> {
    let v: Vec<f32> = text
        .split(',')
        .map(|c| c.trim().parse::<f32>())
        .collect::<Result<_, _>>()
        .map_err(|e| format!("{text:?}: {e}"))?;
    match v[..] {
        [x, y, z] if v.iter().all(|c| c.is_finite()) => Ok(glam::Vec3::new(x, y, z)),
        _ => Err(format!("{text:?}: expected three finite numbers \"x,y,z\"")),
    }
}

/// Loads a mesh or a maze under a spinner, printing what the loader survived as warnings.
fn load_subject(path: &Path) -> Result<Subject> {
    let label = format!("loading {}", path.display());
    let (subject, warnings) = with_spinner(&label, || Subject::load(path))?;
    for w in &warnings {
        eprintln!("warning: {w}");
    }
    Ok(subject)
}

/// A reflector given on the command line (and the files it read), or the built-in one.
fn load_reflector(path: Option<&Path>) -> Result<(Option<trompe::Mesh>, Vec<PathBuf>)> {
    let Some(path) = path else {
        return Ok((None, Vec::new()));
    };
    let label = format!("loading {}", path.display());
    let loaded = with_spinner(&label, || trompe::geom::io::load(path))?;
    for w in &loaded.warnings {
        eprintln!("warning: {w}");
    }
    Ok((Some(loaded.mesh), loaded.files))
}

impl BakeArgs {
    /// An octahedral atlas: refuses outputs that are inputs, loads the mesh, bakes, writes.
    /// The one input of a single bake.
    pub(super) fn input(&self) -> Result<&PathBuf> {
        match self.inputs.as_slice() {
            [one] => Ok(one),
            _ => anyhow::bail!(
                "{} inputs: only --octahedral bakes several at once (into the folder -o names)",
                self.inputs.len()
            ),
        }
    }

    /// Refuses outputs that are inputs, loads the input, bakes.
    fn bake(self) -> Result<trompe::impostor::BakeReport> {
        let input = self.input()?.clone();
        let mut plan = OutputPlan::new();
        plan.creating_folders()
            .reads([&input])
            .writes(&self.output, &["json"])
            .writes(self.output.with_extension("exr"), &["exr"])
            .writes(self.output.with_extension("png"), &["png"]);
        let glb = self.output.with_extension("glb");
        if self.glb {
            plan.writes(&glb, &["glb"]);
        }
        plan.check_overwrites()?;
        let subject = load_subject(&input)?;
        check_plan(plan.reads(subject.files()))?;
        plan.make_folders()
            .context("creating the output's folder")?;
        let settings = BakeSettings {
            camera: self.camera.choice(self.k),
            resolution: self.resolution,
            from: self.from,
            distance: self.distance,
            layers: self.layers,
        };
        let report = with_spinner("baking the impostor", || {
            bake(&subject, &settings, &self.output)
        })?;
        if self.glb {
            trompe::impostor::gltf::export(&self.output, &glb, self.geometry.into())
                .with_context(|| format!("writing {}", glb.display()))?;
            crate::output::note(format_args!("wrote {}", glb.display()));
        }
        Ok(report)
    }
}

impl CheckArgs {
    /// Loads the inputs, checks, and returns what was measured.
    fn check(self) -> Result<trompe::eval::check::CheckReport> {
        let subject = load_subject(&self.mesh)?;
        let (reflector, reflector_files) = load_reflector(self.reflector.as_deref())?;
        let mut plan = OutputPlan::new();
        plan.reads(subject.files()).reads(reflector_files);
        if let Some(sidecar) = &self.impostor {
            plan.reads([sidecar.clone(), sidecar.with_extension("exr")]);
        }
        if let Some(o) = &self.output {
            plan.writes(o, &["json"])
                .writes(o.with_extension("exr"), &["exr"]);
        }
        if let Some(m) = &self.misses {
            plan.writes(m, &["png"]);
        }
        check_plan(&plan)?;
        let Some(path) = &self.impostor else {
            let settings = CheckSettings {
                camera: self.camera.choice(self.k),
                resolution: self.resolution,
                reflector,
                distance: self.distance,
                view: self.view,
                sphere_rays: self.sphere_rays,
                layers: self.layers,
                misses: self.misses.is_some(),
            };
            return Ok(check_built(&subject, &settings)?);
        };
        if trompe::sidecar::SidecarKind::of(path)? == trompe::sidecar::SidecarKind::Octahedral {
            bail!(
                "{}: an octahedral atlas's layout; `impostor check --impostor` walks depth-image \
                 impostors (pinhole, orthographic, SPOC, graph camera). Octahedral atlases are \
                 scored against the exact render by turntables: `trompe bench octahedral`",
                path.display()
            );
        }
        let baked = trompe::impostor::file::load(path).context("loading the impostor")?;
        let settings = BakedCheckSettings {
            reflector,
            view: self.view,
            region: self.region,
            rays: self.rays,
            misses: self.misses.is_some(),
        };
        Ok(check_baked(&subject, baked, path, &settings)?)
    }
}
