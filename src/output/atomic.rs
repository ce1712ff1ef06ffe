//! Write-to-temporary-then-rename, and the check that a target can be
//! written at all, made before any work whose result it would hold.

use std::io::Write;
use std::path::{Path, PathBuf};

fn temp_path(path: &Path) -> PathBuf {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    path.with_file_name(format!(".{name}.tmp-{}", std::process::id()))
}

/// Write `path` atomically: `fill` writes into a temporary file, which is
/// renamed over `path` only if everything succeeded.
pub fn write_atomic(
    path: &Path,
    fill: impl FnOnce(&mut std::io::BufWriter<std::fs::File>) -> std::io::Result<()>,
) -> std::io::Result<()> {
    let tmp = temp_path(path);
    let result = (|| {
        let file = std::fs::File::create(&tmp)?;
        let mut w = std::io::BufWriter::new(file);
        fill(&mut w)?;
        w.flush()?;
        w.get_ref().sync_all()?;
        Ok(())
    })();
    match result {
        Ok(()) => std::fs::rename(&tmp, path).inspect_err(|_| {
            let _ = std::fs::remove_file(&tmp);
        }),
        Err(e) => {
            let _ = std::fs::remove_file(&tmp);
            Err(e)
        }
    }
}

/// Write bytes atomically.
pub fn write_bytes_atomic(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    write_atomic(path, |w| w.write_all(bytes))
}

/// Whether `path` can receive a file written by [`write_atomic`], checked
/// before the work that produces it: its extension (case-insensitive) is
/// one of `extensions` (any, if empty), its directory exists and takes a
/// new file (one is created and removed again), and it is not a directory.
/// The message names `path`.
pub fn check_target(path: &Path, extensions: &[&str]) -> Result<(), String> {
    let shown = path.display();
    if !extensions.is_empty() {
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase);
        if !ext.is_some_and(|e| extensions.contains(&e.as_str())) {
            let list: Vec<String> = extensions.iter().map(|e| format!(".{e}")).collect();
            return Err(format!(
                "'{shown}' must end in {}",
                crate::mode::expected(&list.iter().map(String::as_str).collect::<Vec<_>>())
            ));
        }
    }
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    if !dir.is_dir() {
        return Err(format!(
            "cannot write '{shown}': the directory '{}' does not exist",
            dir.display()
        ));
    }
    if path.is_dir() {
        return Err(format!("cannot write '{shown}': it is a directory"));
    }
    let probe = temp_path(path);
    match std::fs::File::create(&probe) {
        Ok(_) => {
            let _ = std::fs::remove_file(&probe);
            Ok(())
        }
        Err(e) => Err(format!(
            "cannot write '{shown}': {}",
            crate::error::io_message(&e)
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn targets_are_checked_for_extension_directory_and_permission() {
        let dir = std::env::temp_dir().join(format!("strata-target-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        assert!(check_target(&dir.join("a.PNG"), &["png", "exr"]).is_ok());
        let e = check_target(&dir.join("a.jpg"), &["png", "exr"]).unwrap_err();
        assert!(e.contains("must end in .png or .exr"), "{e}");
        let e = check_target(&dir.join("nodir/a.png"), &["png"]).unwrap_err();
        assert!(e.contains("does not exist"), "{e}");
        let e = check_target(&dir, &[]).unwrap_err();
        assert!(e.contains("is a directory"), "{e}");
        assert!(check_target(Path::new("relative.csv"), &["csv"]).is_ok());
        // Nothing is left behind by the probe.
        assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 0);
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
