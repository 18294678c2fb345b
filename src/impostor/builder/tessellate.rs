//! Tessellation for curved cameras (paper 1 §3.1; `docs/conventions.md` §2.2): an edge splits at
//! its midpoint while its image strays more than half a pixel from its chord, decided by that
//! edge alone, so triangles sharing it split it alike and no crack opens.

use super::*;
/// Largest projected deviation of an edge's midpoint from its chord, in pixels (§2.2): the
/// tolerance the rasterizer's set-up counts curved triangles by.
pub(super) const MAX_DEVIATION_PX: f64 = crate::raster::STRAIGHT_EDGE_TOLERANCE_PX;
/// Recursion cap of the tessellation per source triangle.
pub(super) const MAX_SPLITS: u32 = 12;
/// Bytes a sub-triangle costs while a [`Tessellation`] is made: its corners and source in a
/// worker's pieces (76) and again once they are joined, then its normals, indices and
/// material (52).
pub const BYTES_PER_SUB_TRIANGLE: u64 = 208;
/// Bytes a sub-triangle holds in a made [`Tessellation`].
const HELD_PER_SUB_TRIANGLE: u64 = 128;
/// Sub-triangles a worker makes between two looks at the memory budget.
const BUDGET_STEP: u64 = 4096;

/// A sub-triangle's source triangle and the barycentrics of its corners in it.
pub type SourceTriangle = (u32, [Vec3; 3]);

impl Tessellation {
    /// Sub-triangles from unshared corners (three positions each) and their sources.
    pub(super) fn new(positions: Vec<Vec3>, source: Vec<SourceTriangle>) -> Tessellation {
        let n = source.len();
        let mesh = Mesh {
            normals: vec![Vec3::Z; positions.len()],
            triangles: (0..n as u32)
                .map(|i| [3 * i, 3 * i + 1, 3 * i + 2])
                .collect(),
            positions,
            uvs: None,
            face_material: vec![0; n],
            materials: vec![Material::default()],
        };
        let held = crate::memory::Held::new(crate::memory::times(n as u64, HELD_PER_SUB_TRIANGLE));
        Tessellation {
            mesh,
            source,
            _held: held,
        }
    }
}

/// A tessellated mesh and, for each of its triangles, the source triangle and the barycentrics
/// of its three corners in it.
pub struct Tessellation {
    /// The sub-triangles (unshared corners).
    pub mesh: Mesh,
    /// `(source triangle, corner barycentrics)` per sub-triangle.
    pub source: Vec<SourceTriangle>,
    /// The account's share for the arrays above.
    _held: crate::memory::Held,
}

/// Splits triangles until every edge's projected midpoint lies within 0.5 px of the midpoint of
/// its projected ends (docs/conventions.md §2.2). Whether an edge splits depends on that edge alone,
/// and it splits at its midpoint, so two triangles sharing an edge split it identically: the
/// tessellation has no T-junctions and the image no cracks.
/// Returns `None` when no edge needs a split (the mesh can be rasterized as it is).
///
/// # Errors
/// When the sub-triangles, counted as they are made ([`BYTES_PER_SUB_TRIANGLE`] each), and
/// what the process holds pass the memory budget: a camera can curve a triangle into up to
/// 2^12 pieces, so the output is not known before it is made; it stops within a few thousand
/// sub-triangles of the limit.
pub fn tessellate<P: Projection>(
    camera: &P,
    mesh: &Mesh,
) -> Result<Option<Tessellation>, crate::memory::OverBudget> {
    tessellate_with(camera, mesh, &mut TessellationScratch::default())
}

/// Per-vertex images and per-triangle split flags, kept by an [`ImpostorBuilder`] between
/// builds: allocating them fresh costs more (page faults) than filling them.
#[derive(Default)]
pub(super) struct TessellationScratch {
    pub(super) projected: Vec<Option<ImagePoint>>,
    pub(super) splits: Vec<bool>,
    /// The account's share for the arrays above, as large as they are.
    held: crate::memory::Held,
}

impl TessellationScratch {
    fn bytes(&self) -> u64 {
        (self.projected.capacity() * size_of::<Option<ImagePoint>>() + self.splits.capacity())
            as u64
    }
}

/// [`tessellate`] with reusable working memory.
pub(super) fn tessellate_with<P: Projection>(
    camera: &P,
    mesh: &Mesh,
    scratch: &mut TessellationScratch,
) -> Result<Option<Tessellation>, crate::memory::OverBudget> {
    // Split decisions depend on the edge alone (see above).
    // Whether edge (a, b), whose ends project to (pa, pb), must split. The camera's cheap
    // bound settles nearly every edge of a detailed mesh without projecting its midpoint.
    let split_projected = |a: Vec3, b: Vec3, pa: &ImagePoint, pb: &ImagePoint| -> bool {
        if (pa.uv - pb.uv).length_squared() < 1.0
            || camera.midpoint_deviation_bound(&[*pa, *pb]) <= MAX_DEVIATION_PX
        {
            return false;
        }
        let m = (a + b) * 0.5;
        camera
            .project(m.as_dvec3())
            .is_some_and(|pm| (pm.uv - (pa.uv + pb.uv) * 0.5).length() > MAX_DEVIATION_PX)
    };
    let needs_split = |a: Vec3, b: Vec3| -> bool {
        match (camera.project(a.as_dvec3()), camera.project(b.as_dvec3())) {
            (Some(pa), Some(pb)) => split_projected(a, b, &pa, &pb),
            _ => false,
        }
    };
    // Most triangles of a detailed mesh need no split (the paper notes this): find them from
    // the projected vertices alone, and give back the mesh untouched when none does.
    let needed = crate::memory::times(
        mesh.positions.len() as u64,
        size_of::<Option<ImagePoint>>() as u64,
    )
    .saturating_add(mesh.triangles.len() as u64);
    if needed > scratch.bytes() {
        crate::memory::check(
            || {
                format!(
                    "tessellating {} triangles for a curved camera",
                    mesh.triangles.len()
                )
            },
            needed - scratch.bytes(),
        )?;
    }
    let TessellationScratch {
        projected,
        splits,
        held,
    } = scratch;
    projected.clear();
    projected.par_extend(
        mesh.positions
            .par_iter()
            .map(|p| camera.project(p.as_dvec3())),
    );
    let projected = &*projected;
    let needs_any_split = |t: usize| {
        let [a, b, c] = mesh.triangles[t].map(|i| i as usize);
        // One bound for the three edges settles nearly every triangle.
        if let (Some(pa), Some(pb), Some(pc)) = (projected[a], projected[b], projected[c])
            && camera.midpoint_deviation_bound(&[pa, pb, pc]) <= MAX_DEVIATION_PX
        {
            return false;
        }
        [(a, b), (b, c), (c, a)]
            .iter()
            .any(|&(i, j)| match (projected[i], projected[j]) {
                (Some(pi), Some(pj)) => {
                    split_projected(mesh.positions[i], mesh.positions[j], &pi, &pj)
                }
                _ => false,
            })
    };
    splits.clear();
    splits.par_extend(
        (0..mesh.triangles.len())
            .into_par_iter()
            .map(needs_any_split),
    );
    held.set((projected.capacity() * size_of::<Option<ImagePoint>>() + splits.capacity()) as u64);
    let splits = &*splits;
    if !splits.contains(&true) {
        return Ok(None);
    }
    // Every worker adds what it made to `made` every BUDGET_STEP sub-triangles and stops when
    // the total no longer fits the budget.
    let made = std::sync::atomic::AtomicU64::new(0);
    let count = mesh.triangles.len();
    let budget = |more: u64| {
        let total = made.fetch_add(more, std::sync::atomic::Ordering::Relaxed) + more;
        crate::memory::check(
            || {
                format!(
                    "tessellating {count} triangles for a curved camera ({total} pieces so far)"
                )
            },
            crate::memory::times(total, BYTES_PER_SUB_TRIANGLE),
        )
    };
    // Fixed chunks of source triangles, tessellated in parallel and concatenated in order.
    let tris: Vec<usize> = (0..mesh.triangles.len()).collect();
    let chunks: Vec<(Vec<Vec3>, Vec<SourceTriangle>)> = tris
        .par_chunks(4096)
        .map(|chunk| {
            let mut positions = Vec::with_capacity(chunk.len() * 3);
            let mut source = Vec::with_capacity(chunk.len());
            let mut stack = Vec::new();
            let mut counted = 0;
            for &t in chunk {
                if (source.len() - counted) as u64 >= BUDGET_STEP {
                    budget((source.len() - counted) as u64)?;
                    counted = source.len();
                }
                if !splits[t] {
                    positions.extend_from_slice(&mesh.corners(t));
                    source.push((t as u32, [Vec3::X, Vec3::Y, Vec3::Z]));
                    continue;
                }
                stack.push((mesh.corners(t), [Vec3::X, Vec3::Y, Vec3::Z], 0u32));
                while let Some((p, b, depth)) = stack.pop() {
                    let edges = [(0, 1), (1, 2), (2, 0)];
                    let split = edges
                        .iter()
                        .filter(|&&(i, j)| depth < MAX_SPLITS && needs_split(p[i], p[j]))
                        .max_by(|&&(i, j), &&(k, l)| {
                            p[i].distance_squared(p[j])
                                .total_cmp(&p[k].distance_squared(p[l]))
                        });
                    match split {
                        None => {
                            positions.extend_from_slice(&p);
                            source.push((t as u32, b));
                        }
                        Some(&(i, j)) => {
                            let (pm, bm) = ((p[i] + p[j]) * 0.5, (b[i] + b[j]) * 0.5);
                            let (mut first, mut second) = ((p, b), (p, b));
                            (first.0[j], first.1[j]) = (pm, bm);
                            (second.0[i], second.1[i]) = (pm, bm);
                            stack.push((second.0, second.1, depth + 1));
                            stack.push((first.0, first.1, depth + 1));
                        }
                    }
                }
            }
            budget((source.len() - counted) as u64)?;
            Ok((positions, source))
        })
        .collect::<Result<_, crate::memory::OverBudget>>()?;
    let mut positions = Vec::new();
    let mut source = Vec::new();
    for (p, s) in chunks {
        positions.extend(p);
        source.extend(s);
    }
    Ok(Some(Tessellation::new(positions, source)))
}
