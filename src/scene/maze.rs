//! Grid mazes (paper 1 §5, Fig. 4 and 9): a floor-plan file, its geometry, and the graph camera
//! that follows its corridors from the entrance.
//!
//! File format (`.maze`, UTF-8 text): one character per cell, one line per row, rows from north
//! (−z) to south (+z), columns from west (−x) to east (+x); cell `(col, row)` is the unit square
//! `[col, col+1] × [row, row+1]` in `x × z`. `#` is a wall (a unit cube, 1 m high), `.` is floor,
//! `S` is the entrance: a floor cell on the border of the maze, where the camera starts, looking
//! into the maze. Lines starting with `;` are comments; trailing spaces count as floor.
//!
//! Invariants: a parsed maze is rectangular (short lines are padded with floor), has exactly one
//! entrance with exactly one floor neighbour, and is at most 256 × 256 cells.

use crate::camera::{CameraError, GraphCamera, Pinhole, Plane};
use crate::geom::{Mesh, cube, plane};
use glam::{DVec3, Mat4, Vec3};
use std::collections::VecDeque;
use std::path::{Path, PathBuf};
use thiserror::Error;

/// Largest maze side, in cells.
pub const MAX_MAZE_SIDE: usize = 256;
/// Eye height of the maze camera, metres.
pub const EYE_HEIGHT: f64 = 0.5;
/// Most frusta in a maze's graph camera (the paper's maze has 15; the demo maze needs 34).
pub const MAX_FRUSTA: usize = 48;

/// Errors from reading a maze.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum MazeError {
    /// The file could not be read.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The cause.
        source: std::io::Error,
    },
    /// The floor plan is not valid.
    #[error("{path}: {element}: {reason}")]
    Invalid {
        /// The file.
        path: PathBuf,
        /// Where (`line 3`, `entrance` …).
        element: String,
        /// What is wrong.
        reason: String,
    },
    /// The camera could not be built.
    #[error("{path}: camera: {source}")]
    Camera {
        /// The file.
        path: PathBuf,
        /// The cause.
        source: CameraError,
    },
}

/// A grid maze.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Maze {
    /// `walls[row][col]`.
    pub walls: Vec<Vec<bool>>,
    /// `(col, row)` of the entrance.
    pub entrance: (usize, usize),
}

const DIRS: [(i64, i64); 4] = [(0, -1), (1, 0), (0, 1), (-1, 0)];

impl Maze {
    /// The maze's geometry with `count` copies of `object` (largest extent half a cell)
    /// standing on floor cells spread along the plan in reading order — paper 1's dynamic maze
    /// scene (§6: "the maze with 4 bunnies").
    pub fn with_objects(&self, object: &Mesh, count: usize) -> Mesh {
        let mut mesh = self.mesh();
        let cells = self.floor_cells();
        let b = object.bounds();
        let scale = 0.5 / b.extent().max_element().max(f32::MIN_POSITIVE);
        let base = Vec3::new(b.center().x, b.min.y, b.center().z);
        for i in 1..=count {
            let Some(&(c, r)) = cells.get(i * cells.len() / (count + 1)) else {
                continue;
            };
            let at = Vec3::new(c as f32 + 0.5, 0.0, r as f32 + 0.5);
            mesh.append(&object.transformed(
                &(glam::Mat4::from_translation(at)
                    * glam::Mat4::from_scale(Vec3::splat(scale))
                    * glam::Mat4::from_translation(-base)),
            ));
        }
        mesh
    }

    /// Parses a floor plan (`path` names it in errors).
    pub fn parse(text: &str, path: &Path) -> Result<Maze, MazeError> {
        let invalid = |element: String, reason: &str| MazeError::Invalid {
            path: path.to_path_buf(),
            element,
            reason: reason.to_string(),
        };
        let mut walls = Vec::new();
        let mut entrance = None;
        for (i, line) in text.lines().enumerate() {
            if line.starts_with(';') {
                continue;
            }
            let row = walls.len();
            let mut cells = Vec::new();
            for (col, ch) in line.chars().enumerate() {
                match ch {
                    '#' => cells.push(true),
                    '.' | ' ' => cells.push(false),
                    'S' => {
                        if entrance.replace((col, row)).is_some() {
                            return Err(invalid(
                                format!("line {}", i + 1),
                                "a second entrance 'S'",
                            ));
                        }
                        cells.push(false);
                    }
                    other => {
                        return Err(invalid(
                            format!("line {}, column {}", i + 1, col + 1),
                            &format!("unknown cell {other:?} (expected '#', '.' or 'S')"),
                        ));
                    }
                }
                if cells.len() > MAX_MAZE_SIDE {
                    return Err(invalid(format!("line {}", i + 1), "more than 256 cells"));
                }
            }
            walls.push(cells);
            if walls.len() > MAX_MAZE_SIDE {
                return Err(invalid(format!("line {}", i + 1), "more than 256 rows"));
            }
        }
        let width = walls.iter().map(Vec::len).max().unwrap_or(0);
        if width == 0 {
            return Err(invalid("file".into(), "no cells"));
        }
        for r in &mut walls {
            r.resize(width, false);
        }
        let entrance = entrance.ok_or_else(|| invalid("entrance".into(), "no 'S' cell"))?;
        let maze = Maze { walls, entrance };
        let (c, r) = entrance;
        if !(c == 0 || r == 0 || c + 1 == maze.width() || r + 1 == maze.height()) {
            return Err(invalid("entrance".into(), "'S' must be on the border"));
        }
        if maze.open_directions(entrance).len() != 1 {
            return Err(invalid(
                "entrance".into(),
                "'S' must have exactly one floor neighbour",
            ));
        }
        Ok(maze)
    }

    /// Reads a `.maze` file.
    pub fn load(path: &Path) -> Result<Maze, MazeError> {
        let text = std::fs::read_to_string(path).map_err(|source| MazeError::Io {
            path: path.to_path_buf(),
            source,
        })?;
        Self::parse(&text, path)
    }

    /// Columns.
    pub fn width(&self) -> usize {
        self.walls[0].len()
    }
    /// Rows.
    pub fn height(&self) -> usize {
        self.walls.len()
    }

    /// The floor cells `(col, row)`, row by row.
    pub fn floor_cells(&self) -> Vec<(usize, usize)> {
        (0..self.height())
            .flat_map(|r| (0..self.width()).map(move |c| (c, r)))
            .filter(|&(c, r)| !self.walls[r][c])
            .collect()
    }

    fn floor(&self, col: i64, row: i64) -> bool {
        col >= 0
            && row >= 0
            && (col as usize) < self.width()
            && (row as usize) < self.height()
            && !self.walls[row as usize][col as usize]
    }

    fn open_directions(&self, (c, r): (usize, usize)) -> Vec<usize> {
        (0..4)
            .filter(|&d| self.floor(c as i64 + DIRS[d].0, r as i64 + DIRS[d].1))
            .collect()
    }

    /// The maze's geometry: a unit cube per wall cell and a floor.
    pub fn mesh(&self) -> Mesh {
        let (w, h) = (self.width() as f32, self.height() as f32);
        let mut m = plane(1).transformed(
            &(Mat4::from_translation(Vec3::new(w / 2.0, 0.0, h / 2.0))
                * Mat4::from_scale(Vec3::new(w, 1.0, h))),
        );
        m.materials[0].base_color = Vec3::new(0.55, 0.5, 0.45);
        let box_ = cube();
        let mut walls = Mesh::default();
        for (row, cells) in self.walls.iter().enumerate() {
            for (col, &wall) in cells.iter().enumerate() {
                if wall {
                    let at =
                        Mat4::from_translation(Vec3::new(col as f32 + 0.5, 0.5, row as f32 + 0.5));
                    let mut b = box_.transformed(&at);
                    b.materials[0].base_color = Vec3::new(0.3, 0.45, 0.7);
                    if walls.positions.is_empty() {
                        walls = b;
                    } else {
                        let first = walls.materials.len();
                        walls.append(&b);
                        // One material for every wall.
                        walls.materials.truncate(first);
                        let n = walls.face_material.len();
                        for f in &mut walls.face_material[n - b.face_material.len()..] {
                            *f = 0;
                        }
                    }
                }
            }
        }
        m.append(&walls);
        m
    }

    /// Where the maze camera stands — [`ROOT_BACK`] cells behind the entrance, at eye height —
    /// and the unit direction it looks in, into the first corridor.
    pub fn entrance_view(&self) -> (DVec3, DVec3) {
        let (c0, r0) = self.entrance;
        let d0 = self.open_directions(self.entrance)[0];
        (
            cell_centre(c0 as i64, r0 as i64) - step(d0) * ROOT_BACK,
            step(d0),
        )
    }

    /// The graph camera that follows the corridors from the entrance by a breadth-first walk
    /// of the maze graph, as in the paper's Fig. 9. The root looks along the first corridor
    /// from behind the entrance. A branch walks straight until its corridor turns or meets a
    /// side corridor; then
    /// - at a turn, its frustum **bends** at the corner cell's diagonal plane, the apex turned
    ///   about the corner so the child looks down the new corridor;
    /// - at a junction, its frustum **splits** at the junction's entry plane into one vertical
    ///   slice per open corridor (left to right, equal widths of the corridor); each slice
    ///   bends into its corridor or continues straight on, seen from an apex a few cells
    ///   behind its face ([`STRAIGHT_APEX_BACK`], [`SIDE_APEX_BACK`]), so that the narrow
    ///   slice fans out over the whole corridor and what lies beyond shrinks slowly.
    ///
    /// Cells are claimed when a branch reaches them, so loops are walked once. At most
    /// [`MAX_FRUSTA`] frusta; `size × size` pixels.
    pub fn graph_camera(&self, size: u32, path: &Path) -> Result<GraphCamera, MazeError> {
        let cam_err = |source| MazeError::Camera {
            path: path.to_path_buf(),
            source,
        };
        let (c0, r0) = self.entrance;
        let d0 = self.open_directions(self.entrance)[0];
        // The root: behind the entrance, its view a little wider than the corridor.
        let (eye, _) = self.entrance_view();
        let fov = 2.0 * (0.55f64 / (ROOT_BACK - 0.5)).atan().to_degrees();
        let root = Pinhole::look_at(
            eye.as_vec3(),
            (eye + step(d0)).as_vec3(),
            Vec3::Y,
            fov,
            size,
            size,
        )
        .map_err(cam_err)?
        .with_near(0.05);
        let mut g = GraphCamera::new(root);
        let mut claimed = vec![vec![false; self.width()]; self.height()];
        claimed[r0][c0] = true;
        let mut queue = VecDeque::from([Branch {
            frustum: 0,
            apex: eye,
            cell: (c0 as i64, r0 as i64),
            dir: d0,
        }]);
        let open = |claimed: &Vec<Vec<bool>>, (c, r): (i64, i64), d: usize| {
            let (nc, nr) = (c + DIRS[d].0, r + DIRS[d].1);
            self.floor(nc, nr) && !claimed[nr as usize][nc as usize]
        };
        while let Some(mut b) = queue.pop_front() {
            let d = b.dir;
            // [left, straight, right] relative to the walking direction.
            let around = [(d + 3) % 4, d, (d + 1) % 4];
            // Walk straight while the corridor neither turns nor branches.
            loop {
                let sides = [around[0], around[2]]
                    .iter()
                    .any(|&t| open(&claimed, b.cell, t));
                if sides || !open(&claimed, b.cell, d) {
                    break;
                }
                b.cell = (b.cell.0 + DIRS[d].0, b.cell.1 + DIRS[d].1);
                claimed[b.cell.1 as usize][b.cell.0 as usize] = true;
            }
            let exits: Vec<usize> = around
                .into_iter()
                .filter(|&t| open(&claimed, b.cell, t))
                .collect();
            if exits.is_empty() || g.frusta().len() + exits.len() > MAX_FRUSTA {
                // The corridor ends here: so does its frustum, at the cell's far side.
                let far = cell_centre(b.cell.0, b.cell.1) + step(d) * 0.5;
                g.end(b.frustum, far, step(d)).map_err(cam_err)?;
                continue;
            }
            let next = |t: usize| (b.cell.0 + DIRS[t].0, b.cell.1 + DIRS[t].1);
            for &t in &exits {
                let (nc, nr) = next(t);
                claimed[nr as usize][nc as usize] = true;
            }
            let corner = cell_centre(b.cell.0, b.cell.1);
            if let [t] = exits[..] {
                // A turn: the apex turned about the corner keeps its distance to it.
                let rel = b.apex - corner;
                let apex = corner + step(t) * rel.dot(step(d)) + DVec3::new(0.0, rel.y, 0.0);
                let k = g
                    .bend(b.frustum, corner, turn_normal(d, t), apex, FACE_EXTENT)
                    .map_err(cam_err)?;
                queue.push_back(Branch {
                    frustum: k,
                    apex,
                    cell: next(t),
                    dir: t,
                });
                continue;
            }
            // A junction: slices of the corridor, cut by vertical planes through the apex.
            let right = step((d + 1) % 4);
            let entry = corner - step(d) * 0.5;
            let n = exits.len();
            let cuts: Vec<Plane> = (1..n)
                .map(|i| {
                    let at = entry + right * (i as f64 / n as f64 - 0.5);
                    let cut = Plane::through(b.apex, (at - b.apex).cross(DVec3::Y).normalize());
                    // Inside: the left of the cut.
                    if cut.eval(at - right) < 0.0 {
                        cut.flipped()
                    } else {
                        cut
                    }
                })
                .collect();
            let eye = DVec3::new(0.0, EYE_HEIGHT - corner.y, 0.0);
            // A straight-on slice is re-aimed from behind its face, so that its narrow slice
            // fans out over the whole corridor; a turning slice keeps the apex until it bends.
            let apexes: Vec<DVec3> = exits
                .iter()
                .enumerate()
                .map(|(i, &t)| {
                    let centre = entry + right * ((i as f64 + 0.5) / n as f64 - 0.5);
                    if t == d {
                        centre - step(d) * STRAIGHT_APEX_BACK + eye
                    } else {
                        b.apex
                    }
                })
                .collect();
            let slices = g
                .split_into(b.frustum, entry, step(d), &cuts, &apexes, FACE_EXTENT)
                .map_err(cam_err)?;
            for ((&t, &slice), &apex) in exits.iter().zip(&slices).zip(&apexes) {
                let branch = if t == d {
                    Branch {
                        frustum: slice,
                        apex,
                        cell: next(t),
                        dir: t,
                    }
                } else {
                    // The slice sees the back half of the new corridor (the side of −d); its
                    // apex sits behind the corner, in line with that side's wall, to fan over
                    // all of it.
                    let apex = corner - step(t) * SIDE_APEX_BACK - step(d) * 0.5 + eye;
                    let k = g
                        .bend(slice, corner, turn_normal(d, t), apex, FACE_EXTENT)
                        .map_err(cam_err)?;
                    Branch {
                        frustum: k,
                        apex,
                        cell: next(t),
                        dir: t,
                    }
                };
                queue.push_back(branch);
            }
        }
        Ok(g)
    }
}

/// One corridor the breadth-first walk still has to follow.
struct Branch {
    /// The frustum looking down it.
    frustum: usize,
    /// That frustum's apex.
    apex: DVec3,
    /// The cell the walk is in.
    cell: (i64, i64),
    /// The walking direction (an index into `DIRS`).
    dir: usize,
}

/// How far behind the entrance the root camera stands, in cells. Every frustum's image is a
/// part of its parent's exit face, so the whole maze beyond the first corridor gets what the
/// root sees of that corridor's far end; the root is kept close so that the entrance, where
/// reflections are seen (paper 1 §6, Fig. 5), gets the most texels. (From 8 cells back the
/// deeper maze got 10× the texels, but the entrance walls, seen grazing, so few that a mirror
/// bunny's reflected rays agreed with the BVH on 73 % instead of 99.9 %.)
pub const ROOT_BACK: f64 = 2.5;

/// How far behind a junction's face, in cells, the slice that goes straight on is seen from:
/// the farther, the less the rest of the corridor shrinks in its slice.
pub const STRAIGHT_APEX_BACK: f64 = 3.0;

/// How far behind the corner, in cells, a slice that turns into a side corridor is seen from.
pub const SIDE_APEX_BACK: f64 = 2.0;

/// Faces reach 1.5 m around each corner: enough for a 1 m corridor, walls hide the rest.
const FACE_EXTENT: f64 = 1.5;

/// The centre of cell `(c, r)` at eye height.
fn cell_centre(c: i64, r: i64) -> DVec3 {
    DVec3::new(c as f64 + 0.5, EYE_HEIGHT, r as f64 + 0.5)
}

/// One cell's step in direction `d`.
fn step(d: usize) -> DVec3 {
    DVec3::new(DIRS[d].0 as f64, 0.0, DIRS[d].1 as f64)
}

/// The normal of the corner diagonal where direction `d` turns into `t` (pointing back toward
/// the incoming corridor).
fn turn_normal(d: usize, t: usize) -> DVec3 {
    -(step(d) + step(t))
}

#[cfg(test)]
mod tests {
    use super::*;

    const MAZE: &str =
        "; a test maze\n#######\nS.....#\n#####.#\n#.....#\n#.#####\n#.....#\n#######\n";

    #[test]
    fn parses_and_follows_the_corridors() {
        let m = Maze::parse(MAZE, Path::new("t.maze")).unwrap();
        assert_eq!((m.width(), m.height(), m.entrance), (7, 7, (0, 1)));
        let g = m.graph_camera(64, Path::new("t.maze")).unwrap();
        // Three turns: east→south, south→west, west→south, south→east.
        assert!(g.frusta().len() >= 4, "{}", g.frusta().len());
        // The end of the last corridor projects through the camera.
        let far = DVec3::new(5.5, 0.5, 5.5);
        assert!(
            g.project(far).is_some(),
            "the camera reaches the last corridor"
        );
        let mesh = m.mesh();
        assert!(mesh.triangle_count() > 12 * 20);
    }

    #[test]
    fn junctions_split_and_generalized_rays_stay_on_their_pixel() {
        let text = "#######\n#.....#\n#.#.#.#\nS.....#\n#.#.#.#\n#.....#\n#######\n";
        let m = Maze::parse(text, Path::new("grid.maze")).unwrap();
        let g = m.graph_camera(48, Path::new("grid.maze")).unwrap();
        let splits = g.frusta().iter().filter(|f| f.children.len() >= 2).count();
        assert!(splits >= 1, "{} frusta, no split", g.frusta().len());
        assert!(g.frusta().len() <= MAX_FRUSTA);
        for py in (0..48).step_by(4) {
            for px in (0..48).step_by(4) {
                let uv = crate::frame::pixel_centre(px as f64, py as f64);
                let mut last = f64::INFINITY;
                for seg in g.ray_path(uv, 2.0).windows(2).skip(1) {
                    // Each segment from its start (the last one ends on a far plane or a
                    // corridor another branch claimed: excluded).
                    for k in 0..8 {
                        let x = seg[0].lerp(seg[1], k as f64 / 8.0);
                        // Frusta may overlap above the walls and inside them, where nothing
                        // is to be seen; the corridors' open space belongs to one frustum.
                        let open = x.y > 0.0
                            && x.y < 1.0
                            && m.floor(x.x.floor() as i64, x.z.floor() as i64);
                        if !open {
                            continue;
                        }
                        let p = g.project(x).unwrap();
                        // 1e-4 px: composed matrices of deep frusta round at ~1e-6 px.
                        assert!(
                            (p.uv - uv).length() < 1e-4,
                            "{uv}: {x} → {} in {:?}; path {:?}; frusta {:?}",
                            p.uv,
                            g.locate(x),
                            g.ray_path(uv, 2.0),
                            g.frusta()
                                .iter()
                                .map(|f| (f.parent, f.apex, f.children.clone()))
                                .collect::<Vec<_>>()
                        );
                        assert!(p.gd <= last * (1.0 + 1e-9), "{uv}: gd rises at {x}");
                        last = p.gd;
                    }
                }
            }
        }
    }

    #[test]
    fn malformed_mazes_are_errors() {
        for (text, expect) in [
            ("#####\n#...#\n#####\n", "no 'S'"),
            ("#S#\n#x#\n###\n", "unknown cell"),
            ("###\n#S.\n###\n", "border"),
            (".S.\n#.#\n###\n", "exactly one floor neighbour"),
            ("S.S\n", "second entrance"),
            ("", "no cells"),
        ] {
            let e = Maze::parse(text, Path::new("bad.maze"))
                .unwrap_err()
                .to_string();
            assert!(
                e.contains("bad.maze") && e.contains(expect),
                "{text:?}: {e}"
            );
        }
        let long = format!("S{}\n", ".".repeat(300));
        assert!(Maze::parse(&long, Path::new("long.maze")).is_err());
    }
}
