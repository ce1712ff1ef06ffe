#!/usr/bin/env python3
"""strata over a folder of real-world model files, as other tools read them.

    python3 tools/sweep_models.py [DIR] [--strata target/release/strata]
        [--timeout 60] [--assimp assimp] [--csv out.csv]

DIR defaults to /usr/share/assimp/models (Debian's assimp-testmodels).
Every .obj, .ply, .gltf and .glb under it is loaded by `strata render`
from a one-object scene (a small image, one sample per pixel, a point
light), with a time limit per file, and classified:

  read            exit 0 (warnings, if any, are counted)
  refused-named   exit 2, naming a feature strata does not support
                  ("is not supported", "not supported")
  refused         exit 2 for any other reason (a malformed file, a
                  missing buffer, an index out of range, ...)
  crash           any other exit status, or a panic message
  timeout         still running after --timeout seconds

Where `assimp` (Debian's assimp-utils) is on the PATH, `assimp info FILE`
says whether assimp reads the file too, and the summary lists the files
assimp reads that strata refuses without naming a feature: those are the
ones to look at. Prints one line per file and a summary; --csv writes the
table.
"""

import argparse
import csv
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

EXTENSIONS = {".obj", ".ply", ".gltf", ".glb"}


def scene_text(model: Path) -> str:
    # TOML basic strings: escape backslashes and quotes in the path.
    quoted = str(model.resolve()).replace("\\", "\\\\").replace('"', '\\"')
    return (
        "[render]\nwidth = 32\nheight = 24\nspp = 1\n\n"
        "[[lights]]\ntype = \"point\"\nposition = [0.0, 10.0, 10.0]\n"
        "intensity = [100.0, 100.0, 100.0]\n\n"
        f"[[objects]]\nmesh = \"{quoted}\"\n"
    )


def run_strata(strata: str, model: Path, work: Path, timeout: float):
    scene = work / "scene.toml"
    scene.write_text(scene_text(model))
    try:
        done = subprocess.run(
            [strata, "render", str(scene), "-o", str(work / "out.png"), "--quiet"],
            capture_output=True,
            text=True,
            errors="replace",
            timeout=timeout,
        )
    except subprocess.TimeoutExpired:
        return "timeout", ""
    err = done.stderr.strip()
    lines = [l for l in err.splitlines() if l.strip()]
    if "panicked" in err or done.returncode not in (0, 2):
        return "crash", err[-300:]
    if done.returncode == 0:
        warnings = [l for l in lines if l.startswith("warning:")]
        return "read", " | ".join(warnings)
    message = lines[-1] if lines else ""
    if "not supported" in message:
        return "refused-named", message
    return "refused", message


def assimp_reads(assimp: str, model: Path, timeout: float):
    try:
        done = subprocess.run(
            [assimp, "info", str(model)],
            capture_output=True,
            text=True,
            errors="replace",
            timeout=timeout,
        )
    except subprocess.TimeoutExpired:
        return None
    return done.returncode == 0


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("dir", nargs="?", default="/usr/share/assimp/models")
    parser.add_argument("--strata", default="target/release/strata")
    parser.add_argument("--timeout", type=float, default=60.0)
    parser.add_argument("--assimp", default="assimp")
    parser.add_argument("--csv")
    args = parser.parse_args()

    root = Path(args.dir)
    models = sorted(
        p for p in root.rglob("*") if p.is_file() and p.suffix.lower() in EXTENSIONS
    )
    if not models:
        print(f"no .obj, .ply, .gltf or .glb files under {root}", file=sys.stderr)
        return 2
    assimp = shutil.which(args.assimp)
    rows = []
    with tempfile.TemporaryDirectory(prefix="strata-sweep-") as tmp:
        work = Path(tmp)
        for model in models:
            kind, detail = run_strata(args.strata, model, work, args.timeout)
            theirs = assimp_reads(assimp, model, args.timeout) if assimp else None
            name = os.path.relpath(model, root)
            rows.append((name, kind, theirs, detail))
            shown = {None: "-", True: "reads", False: "refuses"}[theirs]
            print(f"{kind:14} assimp {shown:8} {name}  {detail[:160]}")

    counts = {}
    for _, kind, _, _ in rows:
        counts[kind] = counts.get(kind, 0) + 1
    print()
    print(f"{len(rows)} files: " + ", ".join(f"{n} {k}" for k, n in sorted(counts.items())))
    warned = sum(1 for _, kind, _, detail in rows if kind == "read" and detail)
    print(f"read with a warning: {warned}")
    if assimp:
        look = [r for r in rows if r[2] and r[1] in ("refused", "crash", "timeout")]
        print(f"assimp reads, strata refuses without naming a feature: {len(look)}")
        for name, kind, _, detail in look:
            print(f"  {name}: {kind}: {detail[:200]}")
    if args.csv:
        with open(args.csv, "w", newline="") as f:
            out = csv.writer(f)
            out.writerow(["file", "strata", "assimp_reads", "detail"])
            out.writerows(rows)
    bad = counts.get("crash", 0) + counts.get("timeout", 0)
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
