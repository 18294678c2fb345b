//! Paper 5's Table 1 regime (360 views of 720 × 576 on a sphere of cameras around a mesh of
//! about a thousand faces, `--scale 1`): the master textures' atlas against the exemplars, in
//! pixels, and where its texels go. The atlas depends only on the cameras and the mesh, so no
//! image is rendered; `trompe master encode` prints the same figures (`docs/master.md`).

use crate::common;
use glam::Vec3;
use trompe::camera::Pinhole;
use trompe::master::layout::{Layout, TexelBudget};
use trompe::views::capture::{CaptureSettings, Rig, rig_centres};

/// The teapot's atlas for the capture at `distance` bounding radii, and its budget.
fn atlas_at(distance: f64) -> (Layout, TexelBudget) {
    let mesh = trompe::geom::io::load(&common::asset("meshes/teapot.obj"))
        .unwrap()
        .mesh;
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
    let layout = Layout::new(&trompe::master::face_sizes(&mesh, &cameras, 1.0));
    let surface = trompe::master::face_surface(&mesh, &cameras, 1.0);
    let budget = TexelBudget::of(&layout, surface);
    (layout, budget)
}

#[test]
fn far_enough_the_masters_hold_fewer_pixels_than_the_exemplars() {
    let exemplar = 720.0 * 576.0;
    let (near, _) = atlas_at(3.0);
    let (far, budget) = atlas_at(6.0);
    let ratio = |l: &Layout| exemplar / (l.width as f64 * l.height as f64);
    println!(
        "exemplars : masters, pixels: {:.2} at 3 radii, {:.2} at 6; {budget}",
        ratio(&near),
        ratio(&far)
    );
    // The reached figure at 6 radii (the paper's 2.4 is not reached; docs/master.md says why).
    assert!(ratio(&far) >= 1.44, "{}", ratio(&far));
    assert!(ratio(&near) < 1.0, "{}", ratio(&near));
    // Where the texels go: the warp to right triangles is the largest share.
    let warp = budget.triangles / budget.surface;
    let boxes = budget.boxes / budget.triangles;
    let packing = budget.atlas / budget.boxes;
    assert!(warp > boxes && warp > packing, "{budget}");
    assert!((1.0..1.2).contains(&packing), "{budget}");
}
