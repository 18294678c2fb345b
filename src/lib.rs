//! trompe
pub mod camera;
pub mod frame;
pub mod geom;
pub mod raster;
pub mod trace;
