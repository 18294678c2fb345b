//! trompe
pub mod camera;
pub mod frame;
pub mod geom;
pub mod raster;
pub mod trace;
pub mod scene;
pub mod render;
pub mod bench;
pub mod report;
pub mod validate;
