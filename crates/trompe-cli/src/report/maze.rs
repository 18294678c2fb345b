//! Section "Graph camera" (paper 1 §5, Fig. 4, 5 and 9): the maze's graph-camera impostor, a top
//! view with the frusta drawn, and the impostor's fidelity on a mirror bunny's reflected rays.

use super::html::{Figure, Section, Table};
use super::{DemoInputs, ReportError, draw_line};
use glam::Vec3;
use std::path::Path;
use trompe::frame::{FrameError, io};

/// The closed outline, seen from above (`x`, `z`), of the convex hull of `points`.
fn floor_hull(points: &[glam::DVec3]) -> Vec<glam::DVec3> {
    let flat: Vec<glam::DVec2> = points.iter().map(|q| glam::DVec2::new(q.x, q.z)).collect();
    let hull = trompe::geom::convex_hull(&flat);
    hull.iter()
        .chain(hull.first())
        .map(|&i| glam::DVec3::new(points[i].x, 0.0, points[i].z))
        .collect()
}

/// Section "Graph camera" (paper 1 Fig. 4 and 9): the maze's graph-camera impostor,
/// and a top view with the frusta drawn.
pub(super) fn section(inputs: &DemoInputs, out: &Path) -> Result<Section, ReportError> {
    use trompe::camera::{Orthographic, Projection};
    use trompe::impostor::{ImpostorCamera, build};
    use trompe::raster::{Fragment, FragmentShader, rasterize};
    let path = inputs.scenes.join("maze.maze");
    let frame_err = |reason: String| {
        ReportError::Frame(FrameError::Codec {
            path: path.clone(),
            reason,
        })
    };
    let maze = trompe::scene::maze::Maze::load(&path).map_err(|e| frame_err(e.to_string()))?;
    let g = maze
        .graph_camera(768, &path)
        .map_err(|e| frame_err(e.to_string()))?;
    let mesh = maze.mesh();
    // Each wall orientation lit differently, and alternate cells a little darker (a point of a
    // wall face is given to the cell behind the face), so the unfolded corridors read in depth.
    let light = Vec3::new(0.5, 0.8, 0.3).normalize();
    let albedo = trompe::impostor::albedo_of(&mesh);
    let color = |s: &trompe::impostor::SurfaceSample| {
        let lit = 0.55 + 0.45 * s.normal.dot(light);
        let cell = s.position - 0.5 * s.normal;
        let odd = (cell.x.floor() + cell.z.floor()).rem_euclid(2.0) > 0.5;
        albedo(s) * lit * if odd { 0.82 } else { 1.0 }
    };
    let imp = build(ImpostorCamera::Graph(g.clone()), &mesh, 0, &color)?;
    io::write_png(&out.join("maze-graph-camera.png"), &imp.color_image())?;
    let splits = g.frusta().iter().filter(|f| f.children.len() >= 2).count();

    // Fidelity in the paper's Fig. 5 setting: a mirror bunny in the first corridor.
    let fidelity = {
        use trompe::eval::fidelity::{ReflectorSetup, check_with};
        use trompe::impostor::WalkMode;
        let bunny = trompe::geom::io::load(&inputs.assets.join("meshes/bunny.obj"))?.mesh;
        let setup =
            ReflectorSetup::in_maze(&maze, &bunny, 384).map_err(|e| frame_err(e.to_string()))?;
        let exact = trompe::trace::Bvh::build(vec![setup.target.clone()])?;
        let rays = setup.rays()?;
        let mut rows = Table::new([
            "walk",
            "rays",
            "agreement",
            "on hits",
            "error, mean / median (texel footprints)",
            "texel visits / ray",
        ]);
        for (name, mode) in [
            ("algorithm 2 (texel walk, per frustum)", WalkMode::Exact),
            ("algorithm 1 (uniform 3-D steps)", WalkMode::Linear),
        ] {
            let r = check_with(&imp, &exact, &rays, mode);
            rows.row([
                name.to_string(),
                r.rays.to_string(),
                format!("{:.2} %", r.agreement() * 100.0),
                format!("{:.2} %", r.hit_agreement() * 100.0),
                format!(
                    "{:.2} / {:.1e}",
                    r.mean_error_footprints, r.median_error_footprints
                ),
                format!("{:.0}", r.texel_visits_per_ray),
            ]);
        }
        rows
    };

    // Top view: an orthographic camera looking down, the frusta drawn over it.
    let (w, h) = (maze.width() as f32, maze.height() as f32);
    let centre = Vec3::new(w / 2.0, 5.0, h / 2.0);
    let top = Orthographic::look_at(
        centre,
        centre - Vec3::Y,
        -Vec3::Z,
        (w.max(h) * 0.55) as f64,
        20.0,
        384,
        384,
    )
    .map_err(|e| frame_err(e.to_string()))?;
    struct Shade<'a, F> {
        mesh: &'a trompe::geom::Mesh,
        color: &'a F,
    }
    impl<F: Fn(&trompe::impostor::SurfaceSample) -> Vec3 + Sync> FragmentShader for Shade<'_, F> {
        type Output = trompe::frame::Rgba;
        fn shade(&self, f: &Fragment) -> trompe::frame::Rgba {
            let t = f.item.triangle as usize;
            let [a, b, c] = self.mesh.triangles[t].map(|i| i as usize);
            let p = self.mesh.positions[a] * f.bary.x
                + self.mesh.positions[b] * f.bary.y
                + self.mesh.positions[c] * f.bary.z;
            let s = trompe::impostor::SurfaceSample {
                position: p,
                normal: self.mesh.face_normal(t),
                uv: glam::Vec2::ZERO,
                triangle: t as u32,
            };
            (self.color)(&s).extend(1.0)
        }
    }
    let (target, _) = rasterize(
        &top,
        &[&mesh],
        &Shade {
            mesh: &mesh,
            color: &color,
        },
        trompe::frame::Rgba::ONE,
    )?;
    let mut view = target.attributes;
    let red = trompe::frame::Rgba::new(1.0, 0.05, 0.05, 1.0);
    let yellow = trompe::frame::Rgba::new(1.0, 0.9, 0.1, 1.0);
    let at = |p: glam::DVec3| top.project(glam::DVec3::new(p.x, 4.0, p.z)).map(|q| q.uv);
    // Each frustum's outline (red; the root yellow): its entry face and the faces where its
    // children begin, seen from above; then a few generalized rays (white, Fig. 9).
    for (k, f) in g.frusta().iter().enumerate() {
        let colour = if k == 0 { yellow } else { red };
        let mut outline: Vec<glam::DVec3> = f.entry_face.clone();
        if f.entry_face.is_empty() {
            outline.push(f.apex);
        }
        for &c in &f.children {
            outline.extend_from_slice(&g.frusta()[c].entry_face);
        }
        if f.children.is_empty() {
            outline.extend(
                f.entry_face
                    .iter()
                    .map(|v| *v + (*v - f.apex).normalize() * 3.0),
            );
        }
        for hull_edge in floor_hull(&outline).windows(2) {
            if let (Some(a), Some(b)) = (at(hull_edge[0]), at(hull_edge[1])) {
                draw_line(&mut view, a, b, colour);
            }
        }
    }
    let white = trompe::frame::Rgba::ONE;
    let (gw, gh) = g.resolution();
    for i in 0..9 {
        let uv = glam::DVec2::new((i as f64 + 0.5) / 9.0 * gw as f64, gh as f64 * 0.55);
        for seg in g.ray_path(uv, 3.0).windows(2) {
            if let (Some(a), Some(b)) = (at(seg[0]), at(seg[1])) {
                draw_line(&mut view, a, b, white);
            }
        }
    }
    io::write_png(&out.join("maze-frusta.png"), &view)?;
    let mut s = Section::new("graph-camera", "Graph camera (paper 1 §5)");
    s.paragraph(format!("A graph camera built from `scenes/maze.maze` by a breadth-first walk of its corridors from the entrance (`docs/conventions.md` §4): {} frusta — a bend at every turn, a split at each of the {} junctions. Left: the impostor it builds, every corridor the walk reached in one continuous image (deeper corridors get fewer pixels, as in the paper's Fig. 12). Right: the maze from above, each frustum outlined between its entry face and the faces of its children (root in yellow), and a few generalized rays in white (Fig. 9).", g.frusta().len(), splits));
    s.figures(vec![
        Figure::new(
            "maze-graph-camera.png",
            format!(
                "graph-camera impostor, {:.1} % of texels covered",
                imp.coverage() * 100.0
            ),
        ),
        Figure::new("maze-frusta.png", "frusta over the maze"),
    ]);
    s.paragraph("Reflected rays of a mirror bunny standing in the first corridor (Fig. 5), answered by the impostor and by the exact BVH (`trompe impostor check scenes/maze.maze --camera graph --reflector assets/meshes/bunny.obj`):");
    s.table(fidelity);
    Ok(s)
}
