//! `trompe relief`: frames written, bad settings refused.

use crate::common;

#[test]
fn the_relief_command_writes_frames_and_refuses_what_it_should() {
    let out = common::scratch("relief-cli");
    let scene = common::root().join("scenes/relief-walk.toml");
    let run = |args: &[&str]| {
        std::process::Command::new(env!("CARGO_BIN_EXE_trompe"))
            .args(args)
            .output()
            .unwrap()
    };
    let dir = out.join("walk");
    let dir_s = dir.to_str().unwrap();
    let ok = run(&[
        "relief",
        scene.to_str().unwrap(),
        "-o",
        dir_s,
        "--frames",
        "6",
        "--resolution",
        "64",
        "--object",
        "bunny",
    ]);
    assert!(
        ok.status.success(),
        "{}",
        String::from_utf8_lossy(&ok.stderr)
    );
    assert!(dir.join("frame_0005.png").is_file());
    let csv = std::fs::read_to_string(dir.join("walk.csv")).unwrap();
    assert_eq!(csv.lines().count(), 1 + 6);
    // An unknown object is named with the ones there are.
    let bad = run(&[
        "relief",
        scene.to_str().unwrap(),
        "-o",
        dir_s,
        "--object",
        "dragon",
    ]);
    assert!(!bad.status.success());
    let err = String::from_utf8_lossy(&bad.stderr);
    assert!(err.contains("\"dragon\"") && err.contains("bunny"), "{err}");
    // A folder of someone else's files is refused.
    let foreign = out.join("foreign");
    std::fs::create_dir_all(&foreign).unwrap();
    std::fs::write(foreign.join("notes.txt"), "mine").unwrap();
    let refused = run(&[
        "relief",
        scene.to_str().unwrap(),
        "-o",
        foreign.to_str().unwrap(),
    ]);
    assert!(!refused.status.success());
    assert_eq!(
        std::fs::read_to_string(foreign.join("notes.txt")).unwrap(),
        "mine"
    );
}
