//! The library's integration tests, one binary (each file a module: one link instead of one a file).

mod common;

mod bad_input;
mod graph;
mod hybrid;
mod impostor;
mod layers;
mod loaders;
mod master_regime;
mod methods;
mod octahedral;
mod peeling;
mod raster_vs_bvh;
mod relief;
mod render;
mod sequence;
mod spoc_kinds;
mod texturing;
mod views;
