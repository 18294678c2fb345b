//! Layered view-dependent projective textures: visibility layers against the exact criterion,
//! the paper's Fig. 2, cycles, OpenRaster round trips and bad files, rendering at an input
//! viewpoint.

use crate::common;

use common::layer_scene::{built, captured};
use common::scratch;
use glam::{Vec3, Vec4};
use std::path::{Path, PathBuf};
use trompe::camera::Pinhole;
use trompe::frame::{Image, io::to_srgb8, metrics};
use trompe::geom::{Material, Mesh};
use trompe::layers::ora::{self, Ora, OraError, OraLayer};
use trompe::layers::order::{OrderSettings, Ordering, order_view, violations};
use trompe::layers::{self, BuildSettings};
use trompe::texturing::BlendSettings;

/// A quad (two triangles) through four corners, in order around it.
fn quad(c: [Vec3; 4]) -> Mesh {
    let n = (c[1] - c[0]).cross(c[3] - c[0]).normalize();
    Mesh {
        positions: c.to_vec(),
        normals: vec![n; 4],
        uvs: None,
        triangles: vec![[0, 1, 2], [0, 2, 3]],
        face_material: vec![0, 0],
        materials: vec![Material::default()],
    }
}

/// A camera at the origin looking down −z, `w × h` pixels, 40° vertical field of view.
fn camera(w: u32, h: u32) -> Pinhole {
    Pinhole::look_at(Vec3::ZERO, Vec3::NEG_Z, Vec3::Y, 40.0, w, h).expect("a camera")
}

/// A quad facing the camera at depth `z` covering pixel columns `a ..= b` of `camera(110, 10)`.
fn strip(a: u32, b: u32, z: f32) -> Mesh {
    let s = 2.0 * (20f32.to_radians()).tan() / 10.0;
    let x = |edge: f32| (edge - 55.0) * s * z;
    let y = 8.0 * s * z;
    quad([
        Vec3::new(x(a as f32), -y, -z),
        Vec3::new(x(b as f32 + 1.0), -y, -z),
        Vec3::new(x(b as f32 + 1.0), y, -z),
        Vec3::new(x(a as f32), y, -z),
    ])
}

#[test]
fn the_papers_fig2_puts_only_a_in_the_first_layer_and_no_layer_is_hidden_by_a_later_one() {
    // docs/conventions.md §9.2: A in front of B; B in front of C and D; C hidden by B only
    // where D, farther, also lies; D seen at one end.
    let mut meshes = vec![
        strip(0, 39, 1.0),
        strip(20, 79, 2.0),
        strip(50, 89, 3.0),
        strip(40, 109, 4.0),
    ];
    for ordering in [Ordering::ItemBuffer, Ordering::Exact] {
        let settings = OrderSettings {
            ordering,
            ..OrderSettings::default()
        };
        let (o, _) = order_view(&camera(110, 10), &mut meshes, &settings).expect("ordered");
        assert_eq!(o.layers[0], vec![0], "{ordering:?}: only A first");
        assert_eq!(o.layers.len(), 4, "{ordering:?}: A, B, C, D one a layer");
        assert!(violations(&o, settings.tolerance).is_empty());
        assert!(o.forced.is_empty() && o.opened.is_empty());
    }
}

#[test]
fn interpenetrating_quads_are_opened_and_split_until_no_triangle_hides_an_earlier_one() {
    // An X seen from the front: each quad is nearer on one half.
    let p = quad([
        Vec3::new(-1.0, -1.0, -2.0),
        Vec3::new(1.0, -1.0, -3.0),
        Vec3::new(1.0, 1.0, -3.0),
        Vec3::new(-1.0, 1.0, -2.0),
    ]);
    let q = quad([
        Vec3::new(-1.0, -1.0, -3.0),
        Vec3::new(1.0, -1.0, -2.0),
        Vec3::new(1.0, 1.0, -2.0),
        Vec3::new(-1.0, 1.0, -3.0),
    ]);
    let mut meshes = vec![p, q];
    let area: f32 = meshes.iter().map(Mesh::area).sum();
    let settings = OrderSettings::default();
    let (o, _) = order_view(&camera(96, 96), &mut meshes, &settings).expect("ordered");
    assert_eq!(o.opened, vec![0, 1], "both objects are in the cycle");
    assert!(!o.splits.is_empty(), "triangles cross: Newell splits");
    assert!(o.forced.is_empty(), "the splits resolve the cycle");
    assert!(violations(&o, settings.tolerance).is_empty());
    let after: f32 = meshes.iter().map(Mesh::area).sum();
    assert!(
        (after - area).abs() < 1e-4 * area,
        "splits keep the surface"
    );
}

/// Pixels a render textured (alpha ½ or more).
fn textured(img: &Image<Vec4>) -> Image<bool> {
    img.map(|p| p.w >= 0.5)
}

#[test]
fn rendering_from_an_input_viewpoint_reproduces_its_photograph() {
    let (scene, views) = captured(4);
    let set = built(&scene, &views, &BuildSettings::default());
    for (i, v) in views.iter().enumerate() {
        let blend = layers::render::render(&v.pinhole(), &set, &BlendSettings::default())
            .expect("rendered");
        assert_eq!(
            blend.holes, 0,
            "view {i}: every pixel it shows is in its layers"
        );
        let photo = v.image.as_ref().expect("captured");
        let psnr = metrics::psnr(&blend.image, photo, Some(&textured(&blend.image))).expect("psnr");
        assert!(psnr >= 40.0, "view {i}: {psnr:.1} dB");
    }
}

#[test]
fn both_orderings_give_the_same_layers_and_the_exact_criterion_holds_in_every_view() {
    let (scene, views) = captured(3);
    let (mut meshes, _) = layers::scene_objects(&scene).expect("objects");
    for v in &views {
        let mut layers_of = Vec::new();
        for ordering in [Ordering::ItemBuffer, Ordering::Exact] {
            let settings = OrderSettings {
                ordering,
                ..OrderSettings::default()
            };
            let (o, _) = order_view(&v.pinhole(), &mut meshes, &settings).expect("ordered");
            assert!(violations(&o, settings.tolerance).is_empty(), "{}", v.name);
            assert!(o.forced.is_empty());
            layers_of.push(o.layers);
        }
        assert_eq!(layers_of[0], layers_of[1], "{}", v.name);
    }
}

#[test]
fn layers_are_the_same_for_one_and_two_threads() {
    let (scene, views) = captured(2);
    let run = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("a pool")
            .install(|| built(&scene, &views, &BuildSettings::default()))
    };
    let (a, b) = (run(1), run(2));
    for (la, lb) in a.layers.iter().zip(&b.layers) {
        assert_eq!(la.assignment, lb.assignment);
        for (x, y) in la.layers.iter().zip(&lb.layers) {
            assert_eq!((&x.name, x.rect), (&y.name, y.rect));
            assert_eq!(x.image.pixels(), y.image.pixels());
        }
    }
}

#[test]
fn the_layers_of_a_view_composite_back_to_its_photograph() {
    let (scene, views) = captured(2);
    let set = built(&scene, &views, &BuildSettings::default());
    let dir = scratch("layers-composite");
    layers::file::save(&dir, &set).expect("saved");
    for v in &set.views {
        let ora = ora::read(&dir.join(layers::file::ora_name(&v.name))).expect("read");
        let composite = ora.composite().expect("composite");
        let photo = v.image.as_ref().expect("photo");
        let opaque = |i: &Image<Vec4>| to_srgb8(&i.map(|p| p.truncate().extend(1.0)));
        assert_eq!(opaque(&composite), opaque(photo));
    }
}

fn sample_ora() -> Ora {
    let mut a = Image::new(7, 5, Vec4::ZERO).expect("7 × 5");
    for y in 0..5 {
        for x in 0..7 {
            a.set(
                x,
                y,
                Vec4::new(x as f32 / 7.0, y as f32 / 5.0, 0.5, (x % 2) as f32),
            );
        }
    }
    let b = Image::new(20, 10, Vec4::new(0.2, 0.3, 0.4, 1.0)).expect("20 × 10");
    Ora {
        width: 20,
        height: 10,
        layers: vec![
            OraLayer {
                name: "L01.01 a & <b>".into(),
                x: 3,
                y: 2,
                image: a,
                visible: true,
            },
            OraLayer {
                name: "background".into(),
                x: 0,
                y: 0,
                image: b,
                visible: true,
            },
        ],
    }
}

#[test]
fn an_ora_written_and_read_back_keeps_pixels_names_and_placements_and_opens_with_its_mimetype() {
    let dir = scratch("layers-ora");
    let path = dir.join("a.ora");
    let ora = sample_ora();
    ora::write(&path, &ora).expect("written");
    let back = ora::read(&path).expect("read");
    assert_eq!((back.width, back.height), (20, 10));
    for (x, y) in ora.layers.iter().zip(&back.layers) {
        assert_eq!(
            (&x.name, x.x, x.y, x.visible),
            (&y.name, y.x, y.y, y.visible)
        );
        assert_eq!(to_srgb8(&x.image), to_srgb8(&y.image));
    }
    // The OpenRaster rule: the first local header is `mimetype`, stored, its content right
    // after the header.
    let bytes = std::fs::read(&path).expect("bytes");
    assert_eq!(&bytes[0..4], b"PK\x03\x04");
    assert_eq!(u16::from_le_bytes([bytes[8], bytes[9]]), 0, "stored");
    let name_len = u16::from_le_bytes([bytes[26], bytes[27]]) as usize;
    let extra_len = u16::from_le_bytes([bytes[28], bytes[29]]) as usize;
    assert_eq!(&bytes[30..30 + name_len], b"mimetype");
    let body = 30 + name_len + extra_len;
    assert_eq!(&bytes[body..body + 16], b"image/openraster");
    // Written again, the same bytes.
    let again = dir.join("b.ora");
    ora::write(&again, &back).expect("written");
    assert_eq!(bytes, std::fs::read(&again).expect("bytes"));
}

/// A zip entry: name and bytes.
type Entry<'a> = (&'a str, Vec<u8>);

/// A zip holding `entries`, `mimetype` first.
fn png(w: u32, h: u32) -> Vec<u8> {
    let img = Image::new(w, h, Vec4::ONE).expect("an image");
    trompe::frame::io::encode_png(&img, Path::new("x.png")).expect("encoded")
}

#[test]
fn a_malformed_or_truncated_ora_is_an_error_that_names_the_entry() {
    let dir = scratch("layers-bad-ora");
    let mime = ("mimetype", b"image/openraster".to_vec());
    let stack = |layer: &str| {
        format!(r#"<image w="20" h="10"><stack>{layer}</stack></image>"#).into_bytes()
    };
    let cases: Vec<(&str, Vec<Entry>, &str)> = vec![
        ("no-stack.ora", vec![mime.clone()], "stack.xml"),
        (
            "no-png.ora",
            vec![
                mime.clone(),
                ("stack.xml", stack(r#"<layer name="a" src="data/a.png"/>"#)),
            ],
            "data/a.png",
        ),
        (
            "outside.ora",
            vec![
                mime.clone(),
                (
                    "stack.xml",
                    stack(r#"<layer name="far" src="data/a.png" x="500" y="0"/>"#),
                ),
                ("data/a.png", png(4, 4)),
            ],
            "far",
        ),
        (
            "bad-png.ora",
            vec![
                mime.clone(),
                ("stack.xml", stack(r#"<layer name="a" src="data/a.png"/>"#)),
                ("data/a.png", b"not a png".to_vec()),
            ],
            "data/a.png",
        ),
        (
            "bad-xml.ora",
            vec![
                mime.clone(),
                ("stack.xml", b"<image w='20' h='10'><stack>".to_vec()),
            ],
            "stack.xml",
        ),
        (
            "not-ora.ora",
            vec![("mimetype", b"image/png".to_vec())],
            "mimetype",
        ),
    ];
    for (file, entries, names) in cases {
        let path = dir.join(file);
        common::zip_of(&path, &entries);
        let err = ora::read(&path).expect_err(file);
        assert!(err.to_string().contains(names), "{file}: {err}");
    }
    // Truncated: half of a good file.
    let good = dir.join("good.ora");
    ora::write(&good, &sample_ora()).expect("written");
    let bytes = std::fs::read(&good).expect("bytes");
    let cut = dir.join("cut.ora");
    std::fs::write(&cut, &bytes[..bytes.len() / 2]).expect("written");
    assert!(matches!(
        ora::read(&cut),
        Err(OraError::Zip { .. } | OraError::Missing { .. })
    ));
}

#[test]
fn a_layer_an_artist_grew_and_moved_keeps_its_placement() {
    let (scene, views) = captured(2);
    let set = built(&scene, &views, &BuildSettings::default());
    let dir = scratch("layers-edit");
    layers::file::save(&dir, &set).expect("saved");
    let (meshes, names) = layers::scene_objects(&scene).expect("objects");
    let cam = scene.camera.at(0.0).expect("camera");
    let before = layers::render::render(
        &cam,
        &layers::file::load(&dir, meshes.clone(), names.clone()).expect("loaded"),
        &BlendSettings::default(),
    )
    .expect("rendered");
    // Grow the first layer of view 0 by 5 transparent texels left and 3 above, as an editor
    // does when the canvas of a layer is enlarged: its offset moves by as much.
    let file = dir.join(layers::file::ora_name(&set.views[0].name));
    let mut ora = ora::read(&file).expect("read");
    let l = &mut ora.layers[0];
    let (w, h) = l.image.size();
    let mut grown = Image::new(w + 5, h + 3, Vec4::ZERO).expect("grown");
    for y in 0..h {
        for x in 0..w {
            grown.set(x + 5, y + 3, l.image.get(x, y));
        }
    }
    l.image = grown;
    l.x -= 5;
    l.y -= 3;
    ora::write(&file, &ora).expect("written");
    let after = layers::render::render(
        &cam,
        &layers::file::load(&dir, meshes, names).expect("loaded"),
        &BlendSettings::default(),
    )
    .expect("rendered");
    assert_eq!(before.image.pixels(), after.image.pixels());
}

#[test]
fn a_colmap_model_of_the_scene_builds_the_same_layers_as_the_capture_it_came_from() {
    let (scene, views) = captured(2);
    let dir = scratch("layers-colmap");
    let model = dir.join("model");
    let set = trompe::views::ViewSet {
        views: views.clone(),
        image_folder: PathBuf::new(),
        warnings: Vec::new(),
        summary: Default::default(),
    };
    trompe::views::capture::write_capture(&model, &set).expect("written");
    let loaded = {
        let mut s = trompe::views::ViewSet::load(&model, None).expect("model");
        s.load_images().expect("images");
        s.views
    };
    let from_model = built(&scene, &loaded, &BuildSettings::default());
    let from_capture = built(&scene, &views, &BuildSettings::default());
    for (a, b) in from_model.layers.iter().zip(&from_capture.layers) {
        assert_eq!(a.assignment, b.assignment);
        let rects = |l: &layers::ViewLayers| l.layers.iter().map(|x| x.rect).collect::<Vec<_>>();
        assert_eq!(rects(a), rects(b));
    }
}
