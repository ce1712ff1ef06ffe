//! strata's integration tests, one crate: each module was its own test
//! binary once, each linking the whole library; one binary links it once
//! (issue 48: a cold `cargo test --release` in minutes). Run one module's
//! tests with a filter: `cargo test --release --test suite slices::`.
//! Modules are named for what they test; `common` holds the helpers they
//! share (its `mod.rs` has a table of its files).

mod adaptive;
mod architecture;
mod bad_input;
mod build_choice;
mod checkpoints_and_parts;
mod cli_arguments;
mod cli_reports;
mod common;
mod csg;
mod degenerate;
mod docs;
mod embree;
mod embree_instances;
mod embree_native;
mod environment;
mod error_sources;
mod gltf_instances;
mod input_files;
mod instance_queries;
mod instancing;
mod kernels;
mod memory;
mod mesh_file_quirks;
mod mesh_queries;
mod model_render;
mod monte_carlo;
mod packets;
mod path_tracing;
mod primitives;
mod python;
mod python_settings;
mod rays_and_trace;
mod render_flags;
mod render_packets;
mod render_properties;
mod scene_parsing;
mod scene_warnings;
mod self_intersection;
mod sizes;
mod slices;
mod slurm;
mod texture_maps;
mod textures;
mod timeline_picture;
