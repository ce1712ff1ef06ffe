//! strata's integration tests, one crate: each module was its own test
//! binary once, each linking the whole library; one binary links it once
//! (issue 48: a cold `cargo test --release` in minutes). Run one module's
//! tests with a filter: `cargo test --release --test suite slices::`.

mod architecture;
mod bad_input;
mod common;
mod csg;
mod csg_reference;
mod degenerate;
mod docs;
mod embree;
mod embree_instances;
mod embree_native;
mod environment;
mod first_contact;
mod first_hour;
mod gltf_instances;
mod instance_queries;
mod instancing;
mod memory;
mod mesh_queries;
mod model_render;
mod monte_carlo;
mod packets;
mod pipeline_features;
mod primitives;
mod python;
mod rays_and_trace;
mod real_files;
mod render_packets;
mod render_properties;
mod robustness;
mod slices;
mod slurm;
mod textures;
mod user_words;
