//! `trompe bench`: which workloads, and the glue that times them
//! ([`crate::bench`]) and prints their figures.

use super::{load_mesh, with_spinner};
use anyhow::Result;
use clap::ValueEnum;
use std::path::PathBuf;

/// `trompe bench`.
#[derive(clap::Args, Debug)]
pub struct BenchArgs {
    /// Which workloads: every one (the default), or one paper's.
    #[arg(value_enum, default_value_t = BenchSuite::All)]
    suite: BenchSuite,
    /// Shorter timings (less stable figures).
    #[arg(long)]
    quick: bool,
    /// Mesh to measure on (default: the shipped 56k-triangle bunny).
    #[arg(long)]
    mesh: Option<PathBuf>,
    /// Time only the SPOC build's goal line (a fresh 512² SPOC impostor beside a depth +
    /// id rasterization through its reference pinhole), this many times, 3 s each; prints
    /// each ratio, then their range and median.
    #[arg(long, value_name = "RUNS",
          value_parser = clap::value_parser!(u32).range(1..=1000))]
    goal: Option<u32>,
    /// With the `gpu` suite: run only these workloads (comma-separated).
    #[arg(long, value_enum, value_delimiter = ',', value_name = "WORKLOADS")]
    only: Vec<crate::bench::gpu::GpuWorkload>,
}

/// The workloads `trompe bench` times.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum BenchSuite {
    /// Every workload.
    All,
    /// The relief impostors' (paper 3): pre-warp, generation, a walk's frames.
    Relief,
    /// Master Texture encoding (paper 5): 360 views of 720 × 576.
    Master,
    /// Hybrid reflections (paper 2): kd-tree construction and reflection rendering, beside exact
    /// and impostor reflections of the same frames.
    C3rc,
    /// Octahedral impostors: 2048² bakes, and turntables against the exact render.
    Octahedral,
    /// Layered projective textures (paper 4): layers of a 100k-triangle scene from two views.
    Layers,
    /// Reflections through impostors (paper 1 §6): frame time against output and impostor
    /// resolution, every method on every reflection scene, the reflected mesh grown 16×.
    Reflect,
    /// Impostor walks (paper 1 §3.2): time and texel visits per ray from 128² to 2048² beside
    /// the exact BVH on the same rays, a mesh 16× larger, depth layers.
    Walks,
    /// Every method of the one list on paper 1's Fig. 2 scene: the first frame and the frames
    /// after it, beside `trace`.
    Methods,
    /// The GPU beside the CPU, on the adapter `--device gpu` opens: the trace method on every
    /// reflection scene and against output resolution, the exact ray query as the mesh grows.
    Gpu,
}

impl BenchArgs {
    /// Times the chosen workloads and prints their figures.
    pub(super) fn run(self) -> Result<()> {
        let BenchArgs {
            suite,
            quick,
            mesh,
            goal,
            only,
        } = self;
        match suite {
            BenchSuite::Octahedral => {
                let inputs = trompe::eval::fixtures::Shipped::locate();
                let figures = with_spinner("timing", || {
                    crate::bench::octahedral::octahedral(&inputs, quick)
                })?;
                crate::output::report("bench", &figures, &figures)?;
            }
            BenchSuite::Reflect => {
                let inputs = trompe::eval::fixtures::Shipped::locate();
                let selection = if quick {
                    crate::bench::reflect::Selection::quick()
                } else {
                    crate::bench::reflect::Selection::full()
                };
                let tables = with_spinner("timing", || {
                    crate::bench::reflect::tables(&inputs, &selection)
                })?;
                crate::output::report("bench", &tables, &tables)?;
            }
            BenchSuite::C3rc => {
                let inputs = trompe::eval::fixtures::Shipped::locate();
                let tables =
                    with_spinner("timing", || crate::bench::hybrid::tables(&inputs, quick))?;
                crate::output::report("bench", &tables, &tables)?;
            }
            BenchSuite::Relief
            | BenchSuite::Master
            | BenchSuite::Layers
            | BenchSuite::Walks
            | BenchSuite::Methods => {
                let inputs = trompe::eval::fixtures::Shipped::locate();
                let (name, figures) = with_spinner("timing", || match suite {
                    BenchSuite::Master => ("master", crate::bench::master::master(&inputs, quick)),
                    BenchSuite::Layers => ("layers", crate::bench::layers::layers(&inputs, quick)),
                    BenchSuite::Walks => ("walks", crate::bench::walks::walks(&inputs, quick)),
                    BenchSuite::Methods => {
                        ("methods", crate::bench::methods::methods(&inputs, quick))
                    }
                    _ => ("relief", crate::bench::relief::relief(&inputs, quick)),
                });
                let report = crate::bench::BenchReport {
                    heading: format!(
                        "trompe bench {name}, {} threads",
                        rayon::current_num_threads()
                    ),
                    figures: figures?,
                };
                crate::output::report("bench", &report, &report)?;
            }
            BenchSuite::Gpu => {
                let inputs = trompe::eval::fixtures::Shipped::locate();
                let (heading, figures) =
                    with_spinner("timing", || crate::bench::gpu::gpu(&inputs, quick, &only))?;
                let report = crate::bench::BenchReport { heading, figures };
                crate::output::report("bench", &report, &report)?;
            }
            BenchSuite::All => {
                let inputs = trompe::eval::fixtures::Shipped::locate();
                let path = mesh.unwrap_or_else(|| inputs.assets.join("meshes/bunny.obj"));
                let m = load_mesh(&path)?;
                match goal {
                    Some(runs) => {
                        let goal = crate::bench::goal(&path, &m, runs)?;
                        crate::output::report("bench", &goal, &goal)?;
                    }
                    None => {
                        let report = crate::bench::run(&path, &m, &inputs, quick)?;
                        crate::output::report("bench", &report, &report)?;
                    }
                }
            }
        }
        Ok(())
    }
}
