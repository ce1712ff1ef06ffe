//! Every size a user or a file gives is weighed against the machine's
//! memory before anything is allocated (issue 62, point 1): an image's
//! sides, a checkpoint's film, a texture's or an environment map's header,
//! an instances file, the parts of a merge, `strata rays -n`. A size past
//! the memory is refused in under a second with exit 2 and one line naming
//! the flag or key, the bytes and the machine's memory, never an abort
//! (`memory allocation of … bytes failed`, exit 134).

use crate::common::process::{repo, strata, strata_ok};
use crate::common::{skipped, stderr, temp_dir};
use std::path::Path;
use std::process::Output;
use std::time::{Duration, Instant};

/// The machine's memory as strata reads it (`MemTotal`), if known.
fn machine_memory() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("MemTotal:"))?;
    Some(line.split_whitespace().nth(1)?.parse::<u64>().ok()? * 1024)
}

/// Whether `need` bytes are past this machine's memory, so that a test of
/// a refusal means something here; says so where they are not.
fn past_memory(test: &str, need: u64) -> bool {
    match machine_memory() {
        Some(m) if m < need => true,
        Some(m) => {
            skipped(test, &format!("this machine's {m} bytes hold {need}"));
            false
        }
        None => {
            skipped(test, "no /proc/meminfo");
            false
        }
    }
}

/// `strata ARGS` in `dir`, which must be refused fast: exit 2, one line
/// naming each of `needles` and the machine's memory, nothing written.
fn refused_fast(dir: &Path, args: &[&str], needles: &[&str]) -> String {
    let start = Instant::now();
    let out: Output = strata(dir, args);
    let took = start.elapsed();
    let err = stderr(&out);
    assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
    assert!(took < Duration::from_secs(1), "{args:?}: took {took:?}");
    assert_eq!(err.trim_end().lines().count(), 1, "{args:?}: {err}");
    for needle in needles.iter().chain(&["memory", "GiB"]) {
        assert!(err.contains(needle), "{args:?}: no '{needle}' in {err}");
    }
    err
}

/// No file but those the test wrote is left in `dir`.
fn nothing_written(dir: &Path, kept: &[&str]) {
    for entry in std::fs::read_dir(dir).unwrap() {
        let name = entry.unwrap().file_name().to_string_lossy().into_owned();
        assert!(kept.contains(&name.as_str()), "left behind: {name}");
    }
}

/// The issue's own command: a 32768×32768 image (88 bytes a pixel, 88
/// GiB) is refused before the scene is read, naming the flags, the bytes
/// and the machine's memory; as the scene file's keys it names their line,
/// as `--set` edits the edits, and a checkpoint's film (no image, still
/// 52 bytes a pixel) is weighed the same way.
#[test]
fn a_huge_image_is_refused_naming_where_its_size_came_from() {
    if !past_memory("sizes::a_huge_image", 52 << 30) {
        return;
    }
    let dir = temp_dir("sizes-image");
    let seed = repo().join("scenes/seed.toml");
    let seed = seed.to_str().unwrap();
    let err = refused_fast(
        &dir,
        &["render", seed, "--width", "32768", "--height", "32768"],
        &[
            "--width 32768 --height 32768",
            "a 32768×32768 image",
            "88.0 GiB",
        ],
    );
    assert!(err.contains("this machine's"), "{err}");
    let text = std::fs::read_to_string(seed).unwrap();
    let big = format!("[render]\nwidth = 32768\nheight = 32768\n{}", {
        let mut rest = String::new();
        let mut in_render = false;
        for line in text.lines() {
            if line.starts_with('[') {
                in_render = line == "[render]";
            }
            if !in_render {
                rest.push_str(line);
                rest.push('\n');
            }
        }
        rest
    });
    std::fs::write(dir.join("big.toml"), big).unwrap();
    refused_fast(
        &dir,
        &["render", "big.toml"],
        &["big.toml: line 2: render.width, render.height: a 32768×32768 image"],
    );
    // A crop of it is only the crop's pixels: rendered.
    strata_ok(
        &dir,
        &[
            "render", "big.toml", "--crop", "0,0,8,8", "-q", "-o", "crop.png",
        ],
    );
    std::fs::remove_file(dir.join("crop.png")).unwrap();
    refused_fast(
        &dir,
        &[
            "render",
            "--set",
            "render.width=32768",
            "--set",
            "render.height=32768",
        ],
        &["--set render.width=32768 --set render.height=32768"],
    );
    refused_fast(
        &dir,
        &[
            "render",
            seed,
            "--width",
            "32768",
            "--height",
            "32768",
            "--spp",
            "64",
            "--checkpoint",
            "ck.strata",
            "-o",
            "part.strata",
        ],
        &["--width 32768 --height 32768", "52 bytes a pixel: its sums"],
    );
    nothing_written(&dir, &["big.toml"]);
}

/// A PNG for `width` × `height` 8-bit RGB whose texels are cut short
/// after their first bytes: all a decoder reads its size from.
fn png_header(width: u32, height: u32) -> Vec<u8> {
    let chunk = |kind: &[u8], data: &[u8]| {
        let body = [kind, data].concat();
        let mut c = (data.len() as u32).to_be_bytes().to_vec();
        c.extend(&body);
        c.extend(crc32(&body).to_be_bytes());
        c
    };
    let mut ihdr = width.to_be_bytes().to_vec();
    ihdr.extend(height.to_be_bytes());
    ihdr.extend([8, 2, 0, 0, 0]);
    let mut png = b"\x89PNG\r\n\x1a\n".to_vec();
    png.extend(chunk(b"IHDR", &ihdr));
    // A zlib stream's header and one empty stored block.
    png.extend(chunk(b"IDAT", &[0x78, 0x01, 0x00, 0x00, 0x00, 0xff, 0xff]));
    png.extend(chunk(b"IEND", &[]));
    png
}

/// PNG's chunk checksum (CRC-32, reflected, polynomial 0xEDB88320).
fn crc32(bytes: &[u8]) -> u32 {
    let mut crc = !0u32;
    for &b in bytes {
        crc ^= u32::from(b);
        for _ in 0..8 {
            crc = if crc & 1 == 1 {
                (crc >> 1) ^ 0xEDB8_8320
            } else {
                crc >> 1
            };
        }
    }
    !crc
}

/// A texture whose header claims 10⁶ × 10⁶ texels and an environment map
/// claiming as many are refused from their headers, naming the key that
/// gave them and the bytes, before a texel is decoded.
#[test]
fn images_claiming_huge_sizes_are_refused_from_their_headers() {
    let dir = temp_dir("sizes-images");
    std::fs::write(dir.join("huge.png"), png_header(1_000_000, 1_000_000)).unwrap();
    std::fs::write(
        dir.join("huge.hdr"),
        b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 1000000 +X 1000000\n\x02\x02",
    )
    .unwrap();
    std::fs::write(
        dir.join("m.obj"),
        "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nusemtl a\nf 1/1 2/2 3/3\n",
    )
    .unwrap();
    std::fs::write(dir.join("m.mtl"), "newmtl a\nmap_Kd huge.png\n").unwrap();
    std::fs::write(
        dir.join("env.toml"),
        "[[lights]]\ntype = \"environment\"\nmap = \"huge.hdr\"\n",
    )
    .unwrap();
    let texture = [
        "m.mtl: line 2",
        "huge.png",
        "a texture of 1000000×1000000 texels",
    ];
    refused_fast(&dir, &["render", "m.obj", "-o", "o.png"], &texture);
    let map = [
        "env.toml: line 3: lights[0].map",
        "an environment map of 1000000×1000000",
    ];
    refused_fast(&dir, &["render", "env.toml", "-o", "o.png"], &map);
    nothing_written(
        &dir,
        &["huge.png", "huge.hdr", "m.obj", "m.mtl", "env.toml"],
    );
}

/// An instances file (here its first rows, then a sparse terabyte) is
/// estimated from its length and first lines, and refused at its scene
/// key before it is read.
#[test]
fn an_instances_file_too_big_for_the_machine_is_refused_before_it_is_read() {
    let dir = temp_dir("sizes-instances");
    std::fs::write(dir.join("m.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    let rows: String = (0..3000)
        .map(|i| format!("1,0,0,{i}, 0,1,0,0, 0,0,1,0\n"))
        .collect();
    std::fs::write(dir.join("i.csv"), rows).unwrap();
    let file = std::fs::OpenOptions::new()
        .write(true)
        .open(dir.join("i.csv"))
        .unwrap();
    file.set_len(1 << 40).unwrap();
    std::fs::write(
        dir.join("s.toml"),
        "[[objects]]\nmesh = \"m.obj\"\ninstances = \"i.csv\"\n",
    )
    .unwrap();
    refused_fast(
        &dir,
        &["render", "s.toml", "-o", "o.png"],
        &[
            "s.toml: line 3: objects[0].instances",
            "a file of 1.0 TiB and about",
        ],
    );
    nothing_written(&dir, &["m.obj", "i.csv", "s.toml"]);
}

/// What a placement is weighed at bounds what it costs: the peak memory
/// of loading and building a hundred thousand of them, per placement.
#[test]
fn a_placement_is_weighed_at_no_less_than_its_measured_peak() {
    if std::fs::write("/proc/self/clear_refs", "5").is_err() {
        skipped(
            "sizes::a_placement_is_weighed",
            "the peak RSS cannot be reset here",
        );
        return;
    }
    let dir = temp_dir("sizes-placement");
    std::fs::write(dir.join("m.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    let n = 100_000;
    let rows: String = (0..n)
        .map(|i| {
            format!(
                "1,0,0,{}, 0,1,0,{}, 0,0,1,{}\n",
                i % 97,
                i / 97 % 89,
                i / 8633
            )
        })
        .collect();
    std::fs::write(dir.join("i.csv"), rows).unwrap();
    std::fs::write(
        dir.join("s.toml"),
        "[[objects]]\nmesh = \"m.obj\"\ninstances = \"i.csv\"\n[render]\nwidth = 8\nheight = 8\n",
    )
    .unwrap();
    strata_ok(
        &dir,
        &[
            "render", "s.toml", "-q", "-o", "o.png", "--stats", "st.json",
        ],
    );
    let stats: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("st.json")).unwrap()).unwrap();
    let peak = ["load_peak_bytes", "build_peak_bytes"]
        .iter()
        .filter_map(|k| stats["memory"][k].as_u64())
        .max()
        .expect("peaks known where the peak can be reset");
    let per = peak as f64 / n as f64;
    let weighed = strata::scene::compile::PLACEMENT_BYTES as f64;
    assert!(
        per <= weighed,
        "{per:.0} bytes a placement at the peak, weighed at {weighed}"
    );
}

/// A merge holds every part's film at once: parts whose films together
/// pass the machine's memory (sparse files of the largest image's
/// length) are refused before any is read, with advice.
#[test]
fn a_merge_past_the_machines_memory_is_refused_before_reading_a_part() {
    let Some(memory) = machine_memory() else {
        skipped("sizes::a_merge", "no /proc/meminfo");
        return;
    };
    let dir = temp_dir("sizes-merge");
    let film = 52u64 << 30; // 32768² pixels × 52 bytes
    let count = memory / film + 1;
    let mut args = vec!["merge".to_string(), "-o".into(), "out.png".into()];
    let mut kept = Vec::new();
    for k in 0..count {
        let name = format!("part{k}.strata");
        let file = std::fs::File::create(dir.join(&name)).unwrap();
        file.set_len(film).unwrap();
        args.push(name.clone());
        kept.push(name);
    }
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    let needles = [
        format!("merging {count} part"),
        "merge a few at a time".to_string(),
    ];
    let needles: Vec<&str> = needles.iter().map(String::as_str).collect();
    refused_fast(&dir, &args, &needles);
    let kept: Vec<&str> = kept.iter().map(String::as_str).collect();
    nothing_written(&dir, &kept);
}

/// `strata rays -n` is weighed before the mesh is read; past one ray set's
/// index range it says the limit.
#[test]
fn a_ray_count_past_the_machines_memory_is_refused_before_the_mesh_is_read() {
    let dir = temp_dir("sizes-rays");
    // The mesh does not exist: the count is refused first.
    let n = u32::MAX.to_string();
    refused_fast(
        &dir,
        &["rays", "all", "none.obj", "-n", &n, "-o", "r.bin"],
        &["-n 4294967295: writing 21474836475 rays"],
    );
    let out = strata(
        &dir,
        &["rays", "all", "none.obj", "-n", "4294967296", "-o", "r.bin"],
    );
    assert_eq!(out.status.code(), Some(2));
    assert!(stderr(&out).contains("-n 4294967296: at most 4294967295 rays of a kind"));
    nothing_written(&dir, &[]);
}
