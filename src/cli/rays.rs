//! `strata rays KIND MESH -n N [--seed S] -o RAYS.bin`: write a ray set for
//! testing intersection (see [`strata::rays`] for the kinds), plus a
//! description `RAYS.bin.json` that names the kind of each ray set in it.
//!
//! ```json
//! { "format": "strata-rays", "mesh": "bunny.obj", "triangles": 69666,
//!   "closed": true, "seed": 1,
//!   "groups": [ { "kind": "edges", "first": 0, "count": 1000, "target_t": 1.0 } ] }
//! ```
//!
//! `closed` says that every edge of every non-degenerate triangle is shared
//! by exactly two consistently wound ones; `target_t` is where a ray
//! reaches the point it was aimed at (`grazing` and `edges`), else null.

use super::CliError;
use clap::Args;
use serde::Serialize;
use std::path::PathBuf;
use std::time::Instant;
use strata::accel::BuildQuality;
use strata::error::InputError;
use strata::math::Ray;
use strata::rays::file::{encode_rays, write_file, RAY_BYTES};
use strata::rays::{generate, topology, RayKind};
use strata::scene::load_mesh_scene;

/// A kind of ray set, or all of them.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum KindArg {
    One(RayKind),
    All,
}

impl std::str::FromStr for KindArg {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        if s == "all" {
            Ok(KindArg::All)
        } else {
            s.parse()
                .map(KindArg::One)
                .map_err(|e| format!("{e}, or all"))
        }
    }
}

#[derive(Debug, Args, Clone)]
pub struct RaysArgs {
    /// random | camera | grazing | edges | inside, or all (N of each, in that order).
    pub kind: KindArg,
    /// Mesh file (.obj, .ply, .gltf, .glb, .off or .stl), used as it is.
    pub mesh: PathBuf,
    /// Rays to write (of each kind, for all).
    #[arg(short, default_value_t = 100_000)]
    pub n: usize,
    /// Seed: the same seed gives the same rays on any machine.
    #[arg(long, default_value_t = 0)]
    pub seed: u32,
    /// Ray file to write; its description goes to the same name plus .json.
    #[arg(short, long)]
    pub output: PathBuf,
    /// No summary line.
    #[arg(short, long)]
    pub quiet: bool,
}

#[derive(Serialize)]
struct Group {
    kind: &'static str,
    first: usize,
    count: usize,
    target_t: Option<f32>,
}

#[derive(Serialize)]
struct Description {
    format: &'static str,
    mesh: String,
    triangles: usize,
    closed: bool,
    seed: u32,
    groups: Vec<Group>,
}

pub fn run(args: RaysArgs) -> Result<(), CliError> {
    super::writable(&args.output, "--output", &[])?;
    let start = Instant::now();
    let kinds: Vec<RayKind> = match args.kind {
        KindArg::One(kind) => vec![kind],
        KindArg::All => RayKind::ALL.to_vec(),
    };
    let total = check_memory(args.n, kinds.len())?;
    let (scene, _) = load_mesh_scene(&args.mesh, BuildQuality::Fastest)?;
    // Ray generation aims at triangles by their file-order index.
    let triangles = scene.geometry.file_order_triangles();
    let mut rays = Vec::new();
    rays.try_reserve_exact(total).map_err(|_| {
        InputError::flag(
            format!("-n {}", args.n),
            format!("cannot allocate {total} rays"),
        )
    })?;
    let mut groups = Vec::new();
    for kind in kinds {
        let set = generate(kind, &triangles, args.n, args.seed)
            .map_err(|e| InputError::file(&args.mesh, format!("cannot make {kind} rays: {e}")))?;
        groups.push(Group {
            kind: kind.name(),
            first: rays.len(),
            count: set.len(),
            target_t: kind.target_t(),
        });
        rays.extend(set);
    }
    let closed = topology::is_closed(&triangles, 0.0);
    let description = Description {
        format: "strata-rays",
        mesh: args.mesh.display().to_string(),
        triangles: triangles.len(),
        closed,
        seed: args.seed,
        groups,
    };
    let json = serde_json::to_string_pretty(&description)
        .map_err(|e| CliError::Internal(e.to_string()))?;
    let mut json_path = args.output.clone().into_os_string();
    json_path.push(".json");
    let json_path = PathBuf::from(json_path);
    write_file(&args.output, &encode_rays(&rays))?;
    write_file(&json_path, json.as_bytes())?;
    if !args.quiet {
        let names: Vec<&str> = description.groups.iter().map(|g| g.kind).collect();
        println!(
            "wrote {} rays ({}) for {} ({} triangles, {}) in {:.2} s -> {} and {}",
            rays.len(),
            names.join(", "),
            args.mesh.display(),
            triangles.len(),
            if closed { "closed" } else { "not closed" },
            start.elapsed().as_secs_f64(),
            args.output.display(),
            json_path.display()
        );
    }
    Ok(())
}

/// Whether `n` rays of each of `kinds` kinds fit in this machine's memory,
/// weighed before the mesh is read: the rays, one kind's set as it is
/// made, and the file's bytes. The rays in all.
fn check_memory(n: usize, kinds: usize) -> Result<usize, CliError> {
    let flag = || format!("-n {n}");
    if u32::try_from(n).is_err() {
        let message = format!("at most {} rays of a kind", u32::MAX);
        return Err(InputError::flag(flag(), message).into());
    }
    let ray = std::mem::size_of::<Ray>() as u128;
    let total = n as u128 * kinds as u128;
    let need = total * (ray + RAY_BYTES as u128) + n as u128 * ray;
    let what = format_args!(
        "writing {total} rays ({} bytes each, and the file's {RAY_BYTES})",
        std::mem::size_of::<Ray>()
    );
    strata::system::budget::check(need, what).map_err(|m| InputError::flag(flag(), m))?;
    // Within the memory, so within usize.
    Ok(total as usize)
}
