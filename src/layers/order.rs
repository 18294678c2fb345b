//! Visibility layers of one view ("Layered view-dependent projective textures" §4.1;
//! docs/conventions.md §9.1–9.2): the items of a scene sorted into layers L₁, L₂, … such that no
//! item of a layer is hidden, even partly, by an item of the same or a later layer.
//!
//! Two orderings give the same layers: the paper's item-buffer loop (Krishnan et al.'s
//! reversed-depth passes with the stencil counting items a pixel, plus the authors' fix that
//! compares the first and the last render) and the exact criterion (an item is completely
//! visible when, at every pixel of its footprint, no remaining item is nearer), which checks it.
//! Both run on the view's [`ABuffer`].
//!
//! The hierarchy of §4.1: items are whole objects first; when no object can be taken, the
//! objects caught in a visibility cycle are replaced by their triangles; when triangles still
//! cycle (interpenetration, cyclic overlap), a triangle of the cycle is split by the plane of
//! another (Newell, Newell and Sancha 1972, [`super::split`]); past the split budget, the
//! cycle's most visible item is put in a layer alone and counted as forced.
//!
//! Invariants: every item with a footprint in the view gets exactly one layer; an item that is
//! not forced is hidden by no item of its own or a later layer; items with no footprint get
//! none; the result does not depend on the thread count.

use super::abuffer::{ABuffer, hides};
use super::split::{Split, split_triangle};
use crate::camera::{Pinhole, Projection};
use crate::frame::FrameError;
use crate::geom::Mesh;
use crate::geom::Plane;
use crate::raster::{Covered, ItemId, fragments};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// What a visibility layer holds: a whole object or one triangle of an object the ordering
/// had to open.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum Item {
    /// Object `0` whole.
    Object(u32),
    /// Triangle `triangle` of object `object`.
    Triangle {
        /// The object.
        object: u32,
        /// The triangle in its mesh.
        triangle: u32,
    },
}

impl Item {
    /// The object the item belongs to.
    pub fn object(self) -> u32 {
        match self {
            Item::Object(o) | Item::Triangle { object: o, .. } => o,
        }
    }
}

/// Which algorithm sorts the items.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Ordering {
    /// The paper's: item-buffer passes with reversed depth, then the first-versus-last check.
    ItemBuffer,
    /// The exact criterion, pixel by pixel.
    Exact,
}

/// Settings of the ordering.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OrderSettings {
    /// The algorithm.
    pub ordering: Ordering,
    /// Relative depth under which two surfaces at a pixel do not hide each other.
    pub tolerance: f32,
    /// Most Newell splits a view may make before cycles are broken by force.
    pub max_splits: usize,
}

impl Default for OrderSettings {
    /// The paper's item-buffer ordering, a 10⁻⁴ depth tolerance, 64 splits a view.
    fn default() -> Self {
        OrderSettings {
            ordering: Ordering::ItemBuffer,
            tolerance: 1e-4,
            max_splits: 64,
        }
    }
}

/// The items an object stands for in the A-buffer.
#[derive(Clone, Debug, PartialEq)]
enum ObjectItems {
    Whole(u32),
    Triangles(Vec<u32>),
}

/// One view's visibility layers and what it took to make them.
#[derive(Clone, Debug)]
pub struct Ordered {
    /// Every item ever made (objects opened into triangles stay listed, with no layer).
    pub items: Vec<Item>,
    /// Item indices, layer by layer, front first.
    pub layers: Vec<Vec<u32>>,
    /// Each item's layer (`None`: no footprint in this view, or an object opened).
    pub layer_of: Vec<Option<u32>>,
    /// The A-buffer over the final items.
    pub abuffer: ABuffer,
    /// Objects replaced by their triangles.
    pub opened: Vec<u32>,
    /// Newell splits made, in order (the meshes were changed in place).
    pub splits: Vec<Split>,
    /// Items put into a layer though an item of that layer or a later one hides them.
    pub forced: Vec<u32>,
    /// Item-buffer passes run (first renders and reversed renders).
    pub passes: usize,
}

impl Ordered {
    /// The item that holds triangle `t` of object `o`, if it has a layer.
    pub fn layer_of_triangle(&self, items: &ItemIndex, o: u32, t: u32) -> Option<u32> {
        items.item_of(o, t).and_then(|i| self.layer_of[i as usize])
    }
}

/// Object and triangle to item, for the final items of an [`Ordered`].
#[derive(Clone, Debug)]
pub struct ItemIndex(Vec<ObjectItems>);

impl ItemIndex {
    /// The item of triangle `t` of object `o`.
    pub fn item_of(&self, o: u32, t: u32) -> Option<u32> {
        match self.0.get(o as usize)? {
            ObjectItems::Whole(i) => Some(*i),
            ObjectItems::Triangles(v) => v.get(t as usize).copied(),
        }
    }

    /// Whether object `o` was opened into triangles.
    pub fn is_opened(&self, o: u32) -> bool {
        matches!(self.0.get(o as usize), Some(ObjectItems::Triangles(_)))
    }
}

/// Sorts the objects `meshes` (world space) seen through `camera` into visibility layers.
/// Newell splits change `meshes` in place; they are listed in the result.
///
/// # Errors
/// When the camera's image size is refused.
pub fn order_view(
    camera: &Pinhole,
    meshes: &mut [Mesh],
    settings: &OrderSettings,
) -> Result<(Ordered, ItemIndex), FrameError> {
    let size = camera.resolution();
    let tol = settings.tolerance;
    let mut frags = all_fragments(camera, meshes)?;
    let mut map: Vec<ObjectItems> = (0..meshes.len() as u32).map(ObjectItems::Whole).collect();
    let mut items: Vec<Item> = (0..meshes.len() as u32).map(Item::Object).collect();
    let mut abuffer = build(size, &frags, &map);
    let mut alive = seen(&abuffer, items.len());
    let mut layer_of = vec![None; items.len()];
    let (mut layers, mut opened, mut splits, mut forced) = (vec![], vec![], vec![], vec![]);
    let mut passes = 0;
    while alive.iter().any(|&a| a) {
        let taken = match settings.ordering {
            Ordering::Exact => exact_step(&abuffer, &alive, tol),
            Ordering::ItemBuffer => {
                let (taken, p) = item_buffer_step(&abuffer, &alive, tol, true);
                passes += p;
                taken
            }
        };
        if !taken.is_empty() {
            take(&taken, &mut layers, &mut layer_of, &mut alive);
            continue;
        }
        // Stuck: every remaining item is hidden somewhere. Find the cycles.
        let (sccs, edges) = cycles(&abuffer, &alive, tol);
        let stuck_objects: Vec<u32> = sccs
            .iter()
            .flatten()
            .filter_map(|&i| match items[i as usize] {
                Item::Object(o) => Some(o),
                Item::Triangle { .. } => None,
            })
            .collect();
        if !stuck_objects.is_empty() {
            for &o in &stuck_objects {
                let ObjectItems::Whole(whole) = map[o as usize] else {
                    continue;
                };
                alive[whole as usize] = false;
                let first = items.len() as u32;
                let n = meshes[o as usize].triangle_count() as u32;
                items.extend((0..n).map(|t| Item::Triangle {
                    object: o,
                    triangle: t,
                }));
                map[o as usize] = ObjectItems::Triangles((first..first + n).collect());
                opened.push(o);
            }
            abuffer = build(size, &frags, &map);
            extend_alive(&abuffer, &mut alive, &mut layer_of, items.len());
            continue;
        }
        let mut split_now = Vec::new();
        for scc in &sccs {
            if splits.len() + split_now.len() >= settings.max_splits {
                break;
            }
            if let Some(s) = newell_split(scc, &edges, &items, meshes) {
                split_now.push(s);
            }
        }
        if !split_now.is_empty() {
            for s in split_now {
                let o = s.object as usize;
                let ObjectItems::Triangles(tris) = &mut map[o] else {
                    unreachable!("only opened objects have triangle items")
                };
                for &piece in &s.pieces[1..] {
                    tris.push(items.len() as u32);
                    items.push(Item::Triangle {
                        object: s.object,
                        triangle: piece,
                    });
                }
                splits.push(s);
            }
            frags = all_fragments(camera, meshes)?;
            abuffer = build(size, &frags, &map);
            extend_alive(&abuffer, &mut alive, &mut layer_of, items.len());
            continue;
        }
        // Past the split budget (or no plane separates the cycle): the most visible item of
        // the first cycle goes alone.
        let pool: Vec<u32> = sccs.first().cloned().unwrap_or_else(|| {
            (0..items.len() as u32)
                .filter(|&i| alive[i as usize])
                .collect()
        });
        let (vis, foot) = visible_counts(&abuffer, &alive, tol);
        let best = pool
            .iter()
            .copied()
            .max_by(|&a, &b| {
                let ra = vis[a as usize] as f64 / foot[a as usize].max(1) as f64;
                let rb = vis[b as usize] as f64 / foot[b as usize].max(1) as f64;
                ra.total_cmp(&rb).then(b.cmp(&a))
            })
            .expect("a stuck view has a remaining item");
        forced.push(best);
        take(&[best], &mut layers, &mut layer_of, &mut alive);
    }
    let index = ItemIndex(map);
    Ok((
        Ordered {
            items,
            layers,
            layer_of,
            abuffer,
            opened,
            splits,
            forced,
            passes,
        },
        index,
    ))
}

/// The exact criterion checked on a finished ordering: the pairs `(a, b)` of items where `a`
/// hides `b` at some pixel although `b`'s layer is not after `a`'s, `b` not forced — none, for a
/// correct ordering (sorted, each pair once).
pub fn violations(ordered: &Ordered, tolerance: f32) -> Vec<(u32, u32)> {
    let ab = &ordered.abuffer;
    let layer = |i: u32| ordered.layer_of[i as usize];
    let mut out = per_chunk(ab, |range| {
        let mut out = Vec::new();
        for p in range {
            let here = ab.at(p);
            for (k, a) in here.iter().enumerate() {
                for b in &here[k + 1..] {
                    let wrong = match (layer(a.item), layer(b.item)) {
                        (Some(la), Some(lb)) => lb <= la,
                        _ => false,
                    };
                    if wrong && hides(a.gd, b.gd, tolerance) && !ordered.forced.contains(&b.item) {
                        out.push((a.item, b.item));
                    }
                }
            }
        }
        out
    });
    out.sort_unstable();
    out.dedup();
    out
}

/// Every fragment of the meshes through the camera.
fn all_fragments(camera: &Pinhole, meshes: &[Mesh]) -> Result<Vec<Vec<Covered>>, FrameError> {
    let refs: Vec<&Mesh> = meshes.iter().collect();
    fragments(camera, &refs)
}

fn build(size: (u32, u32), frags: &[Vec<Covered>], map: &[ObjectItems]) -> ABuffer {
    let item_of = |id: ItemId| match map.get(id.object as usize)? {
        ObjectItems::Whole(i) => Some(*i),
        ObjectItems::Triangles(v) => v.get(id.triangle as usize).copied(),
    };
    ABuffer::build(size, frags, &item_of)
}

/// Which of `n` items have a footprint.
fn seen(abuffer: &ABuffer, n: usize) -> Vec<bool> {
    let mut seen = vec![false; n];
    for p in 0..abuffer.pixel_count() {
        for e in abuffer.at(p) {
            seen[e.item as usize] = true;
        }
    }
    seen
}

/// Makes the new items (indices past `alive.len()`) alive when they have a footprint; an
/// item already alive that lost its footprint (a split piece now empty) gets no layer.
fn extend_alive(
    abuffer: &ABuffer,
    alive: &mut Vec<bool>,
    layer_of: &mut Vec<Option<u32>>,
    n: usize,
) {
    let seen = seen(abuffer, n);
    let old = alive.len();
    alive.resize(n, false);
    layer_of.resize(n, None);
    for i in 0..n {
        if i >= old {
            alive[i] = seen[i];
        } else if alive[i] && !seen[i] {
            alive[i] = false;
        }
    }
}

fn take(
    taken: &[u32],
    layers: &mut Vec<Vec<u32>>,
    layer_of: &mut [Option<u32>],
    alive: &mut [bool],
) {
    let k = layers.len() as u32;
    for &i in taken {
        alive[i as usize] = false;
        layer_of[i as usize] = Some(k);
    }
    layers.push(taken.to_vec());
}

/// Runs `f` over the A-buffer's pixel chunks in parallel and concatenates what it returns, in
/// pixel order.
fn per_chunk<T: Send>(
    abuffer: &ABuffer,
    f: impl Fn(std::ops::Range<usize>) -> Vec<T> + Sync + Send,
) -> Vec<T> {
    abuffer
        .chunks()
        .into_par_iter()
        .map(f)
        .collect::<Vec<_>>()
        .into_iter()
        .flatten()
        .collect()
}

/// The exact criterion: the remaining items no remaining item hides anywhere.
pub(crate) fn exact_step(abuffer: &ABuffer, alive: &[bool], tol: f32) -> Vec<u32> {
    let hidden = per_chunk(abuffer, |range| {
        let mut out = Vec::new();
        for p in range {
            let mut front = None;
            for e in abuffer.at(p).iter().filter(|e| alive[e.item as usize]) {
                match front {
                    None => front = Some(e.gd),
                    Some(f) if hides(f, e.gd, tol) => out.push(e.item),
                    Some(_) => {}
                }
            }
        }
        out
    });
    let mut is_hidden = vec![false; alive.len()];
    for i in hidden {
        is_hidden[i as usize] = true;
    }
    (0..alive.len() as u32)
        .filter(|&i| alive[i as usize] && !is_hidden[i as usize])
        .collect()
}

/// Per item, the pixels where no remaining item hides it (what the first, normal-depth render
/// shows of it) and its whole footprint.
fn visible_counts(abuffer: &ABuffer, alive: &[bool], tol: f32) -> (Vec<u32>, Vec<u32>) {
    let marks = per_chunk(abuffer, |range| {
        let mut out = Vec::new();
        for p in range {
            let mut front = None;
            for e in abuffer.at(p).iter().filter(|e| alive[e.item as usize]) {
                let f = *front.get_or_insert(e.gd);
                out.push((e.item, !hides(f, e.gd, tol)));
            }
        }
        out
    });
    let mut vis = vec![0u32; alive.len()];
    let mut foot = vec![0u32; alive.len()];
    for (i, shown) in marks {
        foot[i as usize] += 1;
        vis[i as usize] += shown as u32;
    }
    (vis, foot)
}

/// One layer by the paper's item-buffer loop (docs/conventions.md §9.2): candidates are the
/// items the first render shows; reversed-depth renders of the candidates remove, at every
/// pixel where two of them overlap, the farther one (the one the reversed depth test shows),
/// until none overlap; with `fix`, an item the first render showed only in part is dropped.
/// Returns the layer and the number of renders.
pub(crate) fn item_buffer_step(
    abuffer: &ABuffer,
    alive: &[bool],
    tol: f32,
    fix: bool,
) -> (Vec<u32>, usize) {
    let (vis, foot) = visible_counts(abuffer, alive, tol);
    let mut cand: Vec<bool> = (0..alive.len()).map(|i| alive[i] && vis[i] > 0).collect();
    let mut renders = 1;
    loop {
        renders += 1;
        let removed = per_chunk(abuffer, |range| {
            let mut out = Vec::new();
            for p in range {
                let mut it = abuffer.at(p).iter().filter(|e| cand[e.item as usize]);
                let Some(nearest) = it.next() else { continue };
                if let Some(farthest) = it.next_back()
                    && hides(nearest.gd, farthest.gd, tol)
                {
                    out.push(farthest.item);
                }
            }
            out
        });
        if removed.is_empty() {
            break;
        }
        for i in removed {
            cand[i as usize] = false;
        }
    }
    // The last render shows each candidate's whole footprint (no two overlap any more).
    let taken = (0..alive.len() as u32)
        .filter(|&i| cand[i as usize] && (!fix || vis[i as usize] == foot[i as usize]))
        .collect();
    (taken, renders)
}

/// The visibility cycles among the remaining items: the strongly connected components of more
/// than one item of the graph "a hides b at some pixel", and that graph's edges (sorted).
pub(crate) fn cycles(
    abuffer: &ABuffer,
    alive: &[bool],
    tol: f32,
) -> (Vec<Vec<u32>>, Vec<(u32, u32)>) {
    let mut edges = per_chunk(abuffer, |range| {
        let mut out = Vec::new();
        let mut here: Vec<super::abuffer::Entry> = Vec::new();
        for p in range {
            here.clear();
            here.extend(abuffer.at(p).iter().filter(|e| alive[e.item as usize]));
            for (i, a) in here.iter().enumerate() {
                for b in &here[i + 1..] {
                    if hides(a.gd, b.gd, tol) {
                        out.push((a.item, b.item));
                    }
                }
            }
        }
        out.sort_unstable();
        out.dedup();
        out
    });
    edges.sort_unstable();
    edges.dedup();
    let sccs = strongly_connected(alive.len(), &edges)
        .into_iter()
        .filter(|c| c.len() > 1)
        .collect();
    (sccs, edges)
}

/// Tarjan's strongly connected components of the graph on `n` nodes with sorted `edges`,
/// iteratively; each component sorted, components in discovery order.
fn strongly_connected(n: usize, edges: &[(u32, u32)]) -> Vec<Vec<u32>> {
    let mut start = vec![0usize; n + 1];
    for &(a, _) in edges {
        start[a as usize + 1] += 1;
    }
    for i in 0..n {
        start[i + 1] += start[i];
    }
    const UNSEEN: u32 = u32::MAX;
    let mut index = vec![UNSEEN; n];
    let mut low = vec![0u32; n];
    let mut on_stack = vec![false; n];
    let mut stack = Vec::new();
    let mut out = Vec::new();
    let mut next = 0u32;
    for root in 0..n {
        if index[root] != UNSEEN || start[root] == start[root + 1] {
            continue;
        }
        // (node, next edge to look at)
        let mut call = vec![(root, start[root])];
        index[root] = next;
        low[root] = next;
        next += 1;
        stack.push(root as u32);
        on_stack[root] = true;
        while let Some(&mut (v, ref mut e)) = call.last_mut() {
            if *e < start[v + 1] {
                let w = edges[*e].1 as usize;
                *e += 1;
                if index[w] == UNSEEN {
                    index[w] = next;
                    low[w] = next;
                    next += 1;
                    stack.push(w as u32);
                    on_stack[w] = true;
                    call.push((w, start[w]));
                } else if on_stack[w] {
                    low[v] = low[v].min(index[w]);
                }
                continue;
            }
            call.pop();
            if let Some(&(u, _)) = call.last() {
                low[u] = low[u].min(low[v]);
            }
            if low[v] == index[v] {
                let mut comp = Vec::new();
                while let Some(w) = stack.pop() {
                    on_stack[w as usize] = false;
                    comp.push(w);
                    if w as usize == v {
                        break;
                    }
                }
                comp.sort_unstable();
                out.push(comp);
            }
        }
    }
    out
}

/// A Newell split that breaks cycle `scc`: the first edge `a hides b` of the cycle whose one
/// triangle straddles the other's plane splits that triangle by that plane.
fn newell_split(
    scc: &[u32],
    edges: &[(u32, u32)],
    items: &[Item],
    meshes: &mut [Mesh],
) -> Option<Split> {
    let in_scc = |i: u32| scc.binary_search(&i).is_ok();
    for &(a, b) in edges.iter().filter(|e| in_scc(e.0) && in_scc(e.1)) {
        let (
            Item::Triangle {
                object: oa,
                triangle: ta,
            },
            Item::Triangle {
                object: ob,
                triangle: tb,
            },
        ) = (items[a as usize], items[b as usize])
        else {
            continue;
        };
        for ((o, t), (po, pt)) in [((oa, ta), (ob, tb)), ((ob, tb), (oa, ta))] {
            let c = meshes[po as usize]
                .corners(pt as usize)
                .map(|p| p.as_dvec3());
            let Some(n) = (c[1] - c[0]).cross(c[2] - c[0]).try_normalize() else {
                continue;
            };
            let plane = Plane::through(c[0], n);
            if let Some(s) = split_triangle(&mut meshes[o as usize], o, t, &plane) {
                return Some(s);
            }
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A one-row A-buffer from items given as (first pixel, last pixel, depth z).
    fn strip(items: &[(u32, u32, f32)], width: u32) -> ABuffer {
        let mut band = Vec::new();
        for (i, &(a, b, z)) in items.iter().enumerate() {
            for p in a..=b {
                band.push(Covered {
                    pixel: p,
                    gd: 1.0 / z,
                    item: ItemId {
                        object: i as u32,
                        triangle: 0,
                    },
                });
            }
        }
        ABuffer::build((width, 1), &[band], &|id: ItemId| Some(id.object))
    }

    /// The configuration of the paper's Fig. 2 as docs/conventions.md §9.2 restates it: A in
    /// front of B; B in front of C and D; C hidden by B only where D, farther, also lies; D
    /// seen at one end.
    fn fig2() -> ABuffer {
        strip(&[(0, 3, 1.0), (2, 7, 2.0), (5, 8, 3.0), (4, 10, 4.0)], 11)
    }

    #[test]
    fn fig2_krishnan_alone_takes_a_and_c_the_fix_takes_only_a() {
        let ab = fig2();
        let alive = vec![true; 4];
        assert_eq!(item_buffer_step(&ab, &alive, 1e-4, false).0, vec![0, 2]);
        assert_eq!(item_buffer_step(&ab, &alive, 1e-4, true).0, vec![0]);
        assert_eq!(exact_step(&ab, &alive, 1e-4), vec![0]);
    }

    #[test]
    fn a_cycle_of_three_is_one_component() {
        let edges = vec![(0, 1), (1, 2), (2, 0), (2, 3)];
        let sccs: Vec<_> = strongly_connected(4, &edges)
            .into_iter()
            .filter(|c| c.len() > 1)
            .collect();
        assert_eq!(sccs, vec![vec![0, 1, 2]]);
    }

    #[test]
    fn the_two_orderings_agree_on_random_strips() {
        let mut rng = crate::geom::SplitMix64::new(7);
        for _ in 0..200 {
            let n = 2 + (rng.next_f32() * 6.0) as usize;
            let items: Vec<(u32, u32, f32)> = (0..n)
                .map(|_| {
                    let a = (rng.next_f32() * 30.0) as u32;
                    let len = (rng.next_f32() * 12.0) as u32;
                    (a, (a + len).min(39), 1.0 + rng.next_f32() * 9.0)
                })
                .collect();
            let ab = strip(&items, 40);
            let mut alive = vec![true; n];
            loop {
                let exact = exact_step(&ab, &alive, 1e-4);
                let krishnan = item_buffer_step(&ab, &alive, 1e-4, true).0;
                assert_eq!(exact, krishnan, "{items:?}");
                if exact.is_empty() {
                    break;
                }
                for i in exact {
                    alive[i as usize] = false;
                }
            }
            // Constant depth per item: no cycles, so every item is taken.
            assert!(alive.iter().all(|a| !a), "{items:?}");
        }
    }
}
