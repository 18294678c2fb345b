//! The kd-tree of diffuse points (paper 2 §4): an eight-way recursion that splits a node at the
//! centre of its points' box in all three axes at once, stopping at a minimum point count or a
//! minimum size. Leaves own contiguous runs of the (reordered) points, so a leaf the culling
//! keeps is projected as one slice. Built in object space, the tree stays valid under the
//! object's rigid (indeed any affine) motion: the cameras are moved into object space instead.
//!
//! Invariants: every point lies in exactly one leaf; a node's points (its leaves' together) are
//! one contiguous run; a node's box is the tight box of its points; a node's children are
//! contiguous in `nodes`; construction is deterministic.

use super::points::PointSet;
use glam::Vec3;

/// When a node stops splitting.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TreeSettings {
    /// A node with at most this many points is a leaf (the paper's tables average ~120).
    pub leaf_points: usize,
    /// A node whose box is at most this wide on every axis is a leaf.
    pub leaf_size: f32,
}

impl Default for TreeSettings {
    fn default() -> Self {
        TreeSettings {
            leaf_points: 120,
            leaf_size: 0.0,
        }
    }
}

/// Deepest recursion (a guard against coincident points; splits halve the box).
const MAX_DEPTH: u32 = 32;

/// A node: its box and either its children or its points.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Node {
    /// Box, smallest corner.
    pub lo: Vec3,
    /// Box, largest corner.
    pub hi: Vec3,
    /// First child (inner node) or first point (leaf).
    pub first: u32,
    /// Children (1–8) or points.
    pub count: u32,
    /// Whether `first..first + count` are points.
    pub leaf: bool,
    /// The node's points, leaves under it included: `points.0..points.0 + points.1`.
    pub points: (u32, u32),
}

/// The tree; node 0 is the root (absent for no points).
#[derive(Clone, Debug, Default)]
pub struct KdTree {
    /// Nodes, children contiguous.
    pub nodes: Vec<Node>,
}

/// What a tree looks like (paper 2 Table 1's columns).
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct TreeStats {
    /// Nodes.
    pub nodes: usize,
    /// Leaves.
    pub leaves: usize,
    /// Mean depth of a point's leaf (the root is depth 0).
    pub mean_depth: f64,
    /// Mean points in a leaf.
    pub points_per_leaf: f64,
}

impl KdTree {
    /// Builds the tree over `points` and returns it with the points reordered leaf by leaf.
    pub fn build(points: &PointSet, settings: TreeSettings) -> (KdTree, PointSet) {
        let mut order: Vec<u32> = (0..points.len() as u32).collect();
        let mut tree = KdTree::default();
        if order.is_empty() {
            return (tree, PointSet::default());
        }
        let p = &points.positions;
        let (lo, hi) = bounds(p, &order);
        tree.nodes.push(Node {
            lo,
            hi,
            first: 0,
            count: order.len() as u32,
            leaf: true,
            points: (0, order.len() as u32),
        });
        let mut scratch = vec![0u32; order.len()];
        tree.split(0, 0, p, &mut order, &mut scratch, settings);
        let reordered = points.permuted(&order);
        (tree, reordered)
    }

    /// Splits node `id`, which holds `order[first..first + count]`, recursively.
    fn split(
        &mut self,
        id: usize,
        depth: u32,
        p: &[Vec3],
        order: &mut [u32],
        scratch: &mut [u32],
        settings: TreeSettings,
    ) {
        let node = self.nodes[id];
        let extent = node.hi - node.lo;
        if node.count as usize <= settings.leaf_points
            || extent.max_element() <= settings.leaf_size
            || depth >= MAX_DEPTH
        {
            return;
        }
        let (start, end) = (node.first as usize, (node.first + node.count) as usize);
        let centre = (node.lo + node.hi) * 0.5;
        let octant = |i: u32| {
            let q = p[i as usize];
            (q.x >= centre.x) as usize
                | ((q.y >= centre.y) as usize) << 1
                | ((q.z >= centre.z) as usize) << 2
        };
        // A stable counting sort of the node's points by octant.
        let mut counts = [0usize; 8];
        for &i in &order[start..end] {
            counts[octant(i)] += 1;
        }
        let mut offsets = [0usize; 8];
        for k in 1..8 {
            offsets[k] = offsets[k - 1] + counts[k - 1];
        }
        let mut at = offsets;
        for &i in &order[start..end] {
            let o = octant(i);
            scratch[start + at[o]] = i;
            at[o] += 1;
        }
        order[start..end].copy_from_slice(&scratch[start..end]);
        let first_child = self.nodes.len();
        let mut children = 0;
        for k in 0..8 {
            if counts[k] == 0 {
                continue;
            }
            let s = start + offsets[k];
            let (lo, hi) = bounds(p, &order[s..s + counts[k]]);
            self.nodes.push(Node {
                lo,
                hi,
                first: s as u32,
                count: counts[k] as u32,
                leaf: true,
                points: (s as u32, counts[k] as u32),
            });
            children += 1;
        }
        self.nodes[id] = Node {
            first: first_child as u32,
            count: children,
            leaf: false,
            ..node
        };
        for c in first_child..first_child + children as usize {
            self.split(c, depth + 1, p, order, scratch, settings);
        }
    }

    /// Node counts, depths and leaf sizes.
    pub fn stats(&self) -> TreeStats {
        let mut s = TreeStats {
            nodes: self.nodes.len(),
            ..TreeStats::default()
        };
        if self.nodes.is_empty() {
            return s;
        }
        let (mut points, mut depth_sum) = (0u64, 0u64);
        let mut stack = vec![(0usize, 0u64)];
        while let Some((id, depth)) = stack.pop() {
            let n = self.nodes[id];
            if n.leaf {
                s.leaves += 1;
                points += u64::from(n.count);
                depth_sum += depth * u64::from(n.count);
            } else {
                for c in n.first..n.first + n.count {
                    stack.push((c as usize, depth + 1));
                }
            }
        }
        s.mean_depth = depth_sum as f64 / points.max(1) as f64;
        s.points_per_leaf = points as f64 / s.leaves.max(1) as f64;
        s
    }
}

/// The tight box of `p[i]` for `i` in `ids`.
fn bounds(p: &[Vec3], ids: &[u32]) -> (Vec3, Vec3) {
    ids.iter().fold(
        (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
        |(lo, hi), &i| (lo.min(p[i as usize]), hi.max(p[i as usize])),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::Surface;

    #[test]
    fn every_point_is_in_one_leaf_inside_its_box_and_leaves_are_small() {
        let mesh = crate::geom::icosphere(3);
        let points = super::super::points::sample(&mesh, &Surface::Diffuse(None), 0.02, 3);
        let settings = TreeSettings::default();
        let (tree, sorted) = KdTree::build(&points, settings);
        assert_eq!(sorted.len(), points.len());
        let mut owner = vec![0u32; sorted.len()];
        for n in tree.nodes.iter().filter(|n| n.leaf) {
            assert!(n.count as usize <= settings.leaf_points);
            for i in n.first..n.first + n.count {
                owner[i as usize] += 1;
                let p = sorted.positions[i as usize];
                assert!(p.cmpge(n.lo).all() && p.cmple(n.hi).all());
            }
        }
        assert!(owner.iter().all(|&c| c == 1));
        // Inner nodes' boxes hold their children's, and their point runs are their children's
        // runs end to end.
        for n in tree.nodes.iter().filter(|n| !n.leaf) {
            let mut at = n.points.0;
            for c in &tree.nodes[n.first as usize..(n.first + n.count) as usize] {
                assert!(c.lo.cmpge(n.lo).all() && c.hi.cmple(n.hi).all());
                assert_eq!(c.points.0, at);
                at += c.points.1;
            }
            assert_eq!(at, n.points.0 + n.points.1);
        }
        let s = tree.stats();
        println!("{} points: {s:?}", points.len());
        assert!(s.mean_depth > 1.0 && s.points_per_leaf > 10.0);
        // The same points, the same tree.
        let (again, _) = KdTree::build(&points, settings);
        assert_eq!(again.nodes, tree.nodes);
    }

    #[test]
    fn coincident_points_end_in_one_leaf() {
        let points = PointSet {
            positions: vec![Vec3::ONE; 500],
            normals: vec![Vec3::Y; 500],
            albedo: vec![Vec3::ONE; 500],
        };
        let (tree, _) = KdTree::build(&points, TreeSettings::default());
        assert_eq!(tree.nodes.len(), 1);
        assert!(tree.nodes[0].leaf && tree.nodes[0].count == 500);
    }
}
