//! `trompe views`: what reading a COLMAP model reports.

use crate::common;

#[test]
fn verbose_reports_the_rigs_and_frames_a_model_holds() {
    // COLMAP 4's rig fixture (three cameras on one rig, three frames), without its photographs:
    // the model is read and reported, then the first missing photograph is named.
    let model = common::repo("tests/fixtures/colmap/rig/binary");
    let model = model.to_str().unwrap();
    let teapot = common::asset("meshes/teapot.obj");
    let out = common::trompe(&[
        "-v",
        "views",
        "score",
        model,
        "--mesh",
        teapot.to_str().unwrap(),
    ]);
    assert!(!out.status.success());
    let e = common::stderr(&out);
    assert!(
        e.contains("binary model: 3 cameras, 9 images; 1 rigs, 3 frames: 9 images posed by their frame, 6 of them through a sensor's offset in its rig"),
        "{e}"
    );
    assert!(e.contains("frame1_cam1.png"), "{e}");
}
