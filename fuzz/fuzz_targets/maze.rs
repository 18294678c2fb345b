//! A `.maze` floor plan, parsed and turned into its geometry and graph camera.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    trompe_fuzz::small_budget();
    let p = trompe_fuzz::file("m.maze", data);
    if let Ok(maze) = trompe::scene::maze::Maze::load(&p) {
        let _ = maze.mesh();
        let _ = maze.graph_camera(64, &p);
    }
});
