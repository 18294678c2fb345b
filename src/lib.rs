//! trompe
pub mod bench;
pub mod camera;
pub mod frame;
pub mod geom;
pub mod raster;
pub mod render;
pub mod report;
pub mod scene;
pub mod trace;
pub mod validate;
