//! The command line's tests, one binary (each file a module: one link instead of one a file).

mod common;

mod batch;
mod cli;
mod hybrid;
mod json;
mod layers;
mod master;
mod memory;
mod octahedral;
mod peeling;
mod publish;
mod relief;
mod viewer;
mod views;
