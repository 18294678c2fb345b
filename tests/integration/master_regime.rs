//! Paper 5's Table 1 regime (360 views of 720 × 576 on a sphere of cameras around a mesh of a
//! few hundred to a thousand faces, `--scale 1`): the master textures' atlas against the
//! exemplars, in pixels, and where its texels go. The atlas depends only on the cameras and the
//! mesh, so no image is rendered; `trompe master encode` prints the same figures
//! (`docs/master.md`).

use crate::common;
use glam::Vec3;
use trompe::camera::Pinhole;
use trompe::geom::Mesh;
use trompe::master::layout::{Layout, TexelBudget};
use trompe::views::capture::{CaptureSettings, Rig, rig_centres};

/// Pixels of one exemplar.
const EXEMPLAR: f64 = 720.0 * 576.0;

/// The atlas of `mesh` for the capture at `distance` bounding radii, and its budget.
fn atlas_at(mesh: &Mesh, distance: f64) -> (Layout, TexelBudget) {
    let b = mesh.bounds();
    let settings = CaptureSettings {
        rig: Rig::Sphere,
        count: 360,
        size: (720, 576),
        distance,
        ..CaptureSettings::default()
    };
    let centre = b.center();
    let cameras: Vec<Pinhole> = rig_centres(&settings, centre.as_dvec3(), b.radius() as f64)
        .into_iter()
        .map(|eye| {
            // As the capture stands them: straight up or down, "up" is +z.
            let up = match (eye.as_vec3() - centre).normalize().y.abs() > 0.999 {
                true => Vec3::Z,
                false => Vec3::Y,
            };
            Pinhole::look_at(eye.as_vec3(), centre, up, settings.fov_y, 720, 576).unwrap()
        })
        .collect();
    let layout = Layout::new(&trompe::master::face_shapes(mesh, &cameras, 1.0));
    let surface = trompe::master::face_surface(mesh, &cameras, 1.0);
    let budget = TexelBudget::of(&layout, surface);
    (layout, budget)
}

/// Exemplars : masters, in pixels.
fn ratio(l: &Layout) -> f64 {
    EXEMPLAR / (l.width as f64 * l.height as f64)
}

#[test]
fn far_enough_the_masters_hold_fewer_pixels_than_the_exemplars() {
    let mesh = trompe::geom::io::load(&common::asset("meshes/teapot.obj"))
        .unwrap()
        .mesh;
    let (near, _) = atlas_at(&mesh, 3.0);
    let (far, budget) = atlas_at(&mesh, 6.0);
    println!(
        "teapot, {} faces: exemplars : masters, pixels: {:.2} at 3 radii, {:.2} at 6; {budget}",
        mesh.triangle_count(),
        ratio(&near),
        ratio(&far)
    );
    // Paper 5's goal, masters at most half the exemplars' pixels, reached at 6 radii (2.42 : 1;
    // the paper's Table 1 has 2.4 : 1 for 436 faces).
    assert!(ratio(&far) >= 2.4, "{}", ratio(&far));
    assert!(ratio(&near) < 1.0, "{}", ratio(&near));
    // Where the texels go: the right angle at each face's widest corner leaves the warp near
    // the surface (what it adds is the stretch that keeps every direction sampled at the
    // scale); the gutters and borders of small faces' boxes are now the largest share.
    let warp = budget.triangles / budget.surface;
    let boxes = budget.boxes / budget.triangles;
    let packing = budget.atlas / budget.boxes;
    assert!(warp < 1.3, "{budget}");
    assert!(boxes > warp && boxes > packing, "{budget}");
    assert!((1.0..1.2).contains(&packing), "{budget}");
}

/// The paper's own face count: the decimated Stanford bunny simplified by meshoptimizer to 500
/// faces (its scan-like, uneven triangles).
#[test]
fn a_mesh_of_the_papers_size_keeps_its_masters_under_half_the_exemplars() {
    let full = trompe::geom::io::load(&common::shared("meshes/bunny_lowres.obj"))
        .unwrap()
        .mesh;
    let indices: Vec<u32> = full.triangles.iter().flatten().copied().collect();
    let vertices =
        meshopt::VertexDataAdapter::new(bytemuck::cast_slice(&full.positions), 12, 0).unwrap();
    let kept = meshopt::simplify(
        &indices,
        &vertices,
        500 * 3,
        1.0,
        meshopt::SimplifyOptions::None,
        None,
    );
    let triangles: Vec<[u32; 3]> = kept.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
    let count = triangles.len();
    assert!((400..=700).contains(&count), "{count} faces");
    let mesh = Mesh::from_parts(
        std::path::Path::new("bunny_lowres.obj"),
        full.positions.clone(),
        None,
        None,
        triangles,
        vec![0; count],
        Vec::new(),
        &mut Vec::new(),
    )
    .unwrap();
    let (far, budget) = atlas_at(&mesh, 6.0);
    println!(
        "bunny, {count} faces: exemplars : masters, pixels: {:.2} at 6 radii; {budget}",
        ratio(&far)
    );
    // Paper 5's goal is 2 : 1; reached 2.09 : 1 (its thin triangles take the warp to × 1.49).
    assert!(ratio(&far) >= 2.05, "{}", ratio(&far));
}
