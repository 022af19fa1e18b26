//! Atomic file output: write to a temporary file in the same folder, then rename,
//! so a reader never sees a half-written file. [`write_under`] also refuses a
//! relative path that would leave its root (issue 22: defence in depth behind
//! the sanitised names of the report's `file_stem`).

use std::io::Write;
use std::path::{Component, Path, PathBuf};

/// Why `rel` cannot be written under an output folder, if it cannot: it must be
/// relative, made of plain names only (no `..`, `.`, root or prefix), none
/// holding NUL nor longer than 255 bytes.
pub fn check_relative(rel: &Path) -> Result<(), String> {
    if rel.as_os_str().is_empty() {
        return Err("empty path".into());
    }
    for c in rel.components() {
        match c {
            Component::Normal(n) => {
                let n = n.to_string_lossy();
                if n.contains('\0') {
                    return Err("a NUL byte in the name".into());
                }
                if n.len() > 255 {
                    return Err(format!("a name of {} bytes (at most 255)", n.len()));
                }
            }
            _ => return Err("the path would leave the output folder (expected plain names, no '..', '.' or root)".into()),
        }
    }
    Ok(())
}

/// Write `bytes` to `root/rel` atomically, after [`check_relative`] of `rel` and
/// [`check_no_link`] of its folders.
pub fn write_under(root: &Path, rel: &Path, bytes: &[u8]) -> std::io::Result<()> {
    let refuse = |why| std::io::Error::new(std::io::ErrorKind::InvalidInput, why);
    check_relative(rel).map_err(refuse)?;
    check_no_link(root, rel).map_err(refuse)?;
    write_atomic(&root.join(rel), bytes)
}

/// Why `root/rel` would be written through a symbolic link, if it would: a
/// folder between `root` and the file that already exists as a link (say
/// `out/plots -> /etc`) would carry the write outside the output folder. The
/// file itself may be a link: the rename replaces the link, not its target.
pub fn check_no_link(root: &Path, rel: &Path) -> Result<(), String> {
    let mut at = root.to_path_buf();
    let folders = rel.parent().into_iter().flat_map(|p| p.components());
    for c in folders {
        at.push(c);
        match std::fs::symlink_metadata(&at) {
            Ok(m) if m.file_type().is_symlink() => {
                return Err(format!(
                    "{} is a symbolic link: refusing to write through it (outputs stay under the output folder)",
                    at.display()
                ));
            }
            _ => {}
        }
    }
    Ok(())
}

/// Write a set of files under `root` as one step, as far as a file system
/// allows: every file is first staged beside its place (a temporary sibling,
/// written and synced), and only once all are staged are they renamed into place,
/// one after the other (no I/O wait between the renames). So a failure while
/// staging — a full disk, a file where a folder should be — or a run killed
/// before its renames replaces nothing: the temporaries are removed (a killed
/// run's by the next run that writes the same names), and so are the folders
/// this call created, when left empty. Each path is checked first
/// ([`check_relative`], [`check_no_link`]). On failure: the path and the error.
pub fn write_set_under(root: &Path, files: &[(PathBuf, Vec<u8>)]) -> Result<(), (PathBuf, std::io::Error)> {
    let refuse = |rel: &Path, why| (root.join(rel), std::io::Error::new(std::io::ErrorKind::InvalidInput, why));
    for (rel, _) in files {
        check_relative(rel).map_err(|why| refuse(rel, why))?;
        check_no_link(root, rel).map_err(|why| refuse(rel, why))?;
    }
    let (mut created, mut staged) = (Vec::new(), Vec::new());
    let mut swept: Vec<PathBuf> = Vec::new();
    let result = (|| {
        for (rel, bytes) in files {
            let path = root.join(rel);
            let dir = path.parent().unwrap_or(root);
            create_folders(dir, &mut created)?;
            let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_else(|| "out".into());
            if !swept.iter().any(|d| d == dir) {
                let names: Vec<String> = files
                    .iter()
                    .map(|(r, _)| root.join(r))
                    .filter(|p| p.parent().unwrap_or(root) == dir)
                    .filter_map(|p| p.file_name().map(|n| n.to_string_lossy().into_owned()))
                    .collect();
                remove_stale_temporaries(dir, &names);
                swept.push(dir.to_path_buf());
            }
            let tmp = dir.join(format!(".{name}.tmp-{}", std::process::id()));
            staged.push((tmp.clone(), path.clone()));
            write_synced(&tmp, bytes).map_err(|e| (path.clone(), e))?;
        }
        for (tmp, path) in &staged {
            std::fs::rename(tmp, path).map_err(|e| (path.clone(), e))?;
        }
        Ok(())
    })();
    if result.is_err() {
        for (tmp, _) in &staged {
            let _ = std::fs::remove_file(tmp);
        }
        for dir in created.iter().rev() {
            let _ = std::fs::remove_dir(dir);
        }
    }
    result
}

/// Create `dir` and the folders above it that are missing, noting each one
/// created (top first); a file where a folder is needed is named as such.
fn create_folders(dir: &Path, created: &mut Vec<PathBuf>) -> Result<(), (PathBuf, std::io::Error)> {
    let mut missing = Vec::new();
    for at in dir.ancestors().filter(|a| !a.as_os_str().is_empty()) {
        match std::fs::metadata(at) {
            Ok(m) if m.is_dir() => break,
            Ok(_) => {
                let e = std::io::Error::new(std::io::ErrorKind::AlreadyExists, "a file is there, not a folder");
                return Err((at.to_path_buf(), e));
            }
            Err(_) => missing.push(at.to_path_buf()),
        }
    }
    for at in missing.into_iter().rev() {
        match std::fs::create_dir(&at) {
            Ok(()) => created.push(at),
            Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists && at.is_dir() => {}
            Err(e) => return Err((at, e)),
        }
    }
    Ok(())
}

/// Remove the temporaries `.NAME.tmp-PID` in `dir` that a killed run left: those
/// of a process that no longer runs (known from `/proc`; elsewhere none is
/// removed, as a live run's may not be), for the `names` the set writes there.
/// One read of the folder per set.
fn remove_stale_temporaries(dir: &Path, names: &[String]) {
    let proc_fs = Path::new("/proc/self").exists();
    let Ok(entries) = std::fs::read_dir(dir) else { return };
    for entry in entries.flatten() {
        let file = entry.file_name().to_string_lossy().into_owned();
        let Some(pid) = file
            .strip_prefix('.')
            .and_then(|f| f.rsplit_once(".tmp-"))
            .filter(|(name, _)| names.iter().any(|n| n == name))
            .map(|(_, pid)| pid)
            .filter(|p| !p.is_empty() && p.bytes().all(|b| b.is_ascii_digit()))
        else {
            continue;
        };
        if proc_fs && !Path::new("/proc").join(pid).exists() {
            let _ = std::fs::remove_file(entry.path());
        }
    }
}

/// Write `bytes` to a new file at `path` and sync it to the disk.
fn write_synced(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    let mut f = std::fs::File::create(path)?;
    f.write_all(bytes)?;
    f.sync_all()
}

/// Write `bytes` to `path` atomically (temporary sibling, fsync, rename).
pub fn write_atomic(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    let dir = path.parent().filter(|p| !p.as_os_str().is_empty());
    let dir = dir.unwrap_or_else(|| Path::new("."));
    std::fs::create_dir_all(dir)?;
    let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_else(|| "out".into());
    let tmp = dir.join(format!(".{name}.tmp-{}", std::process::id()));
    let result = write_synced(&tmp, bytes).and_then(|()| std::fs::rename(&tmp, path));
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn writes_and_replaces_without_leaving_temporaries() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("a/b.txt");
        write_atomic(&p, b"one").unwrap();
        write_atomic(&p, b"two").unwrap();
        assert_eq!(std::fs::read(&p).unwrap(), b"two");
        let n = std::fs::read_dir(p.parent().unwrap()).unwrap().count();
        assert_eq!(n, 1, "a temporary file was left behind");
    }

    // issue 22: a path that leaves the root is refused and nothing is written.
    #[test]
    fn refuses_paths_that_leave_the_root() {
        let dir = tempfile::tempdir().unwrap();
        let root = dir.path().join("out");
        for bad in ["../x.png", "/tmp/x.png", "plots/../../x", "./x", "a\0b", ""] {
            assert!(write_under(&root, Path::new(bad), b"x").is_err(), "{bad:?}");
        }
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
        write_under(&root, Path::new("plots/a.svg"), b"x").unwrap();
        assert!(root.join("plots/a.svg").exists());
    }

    // A folder under the output that is a link to elsewhere is not written through;
    // a file that is a link is replaced, its target left alone.
    #[cfg(unix)]
    #[test]
    fn refuses_to_write_through_a_linked_folder() {
        let dir = tempfile::tempdir().unwrap();
        let (root, elsewhere) = (dir.path().join("out"), dir.path().join("elsewhere"));
        std::fs::create_dir_all(&root).unwrap();
        std::fs::create_dir_all(&elsewhere).unwrap();
        std::os::unix::fs::symlink(&elsewhere, root.join("plots")).unwrap();
        let err = write_under(&root, Path::new("plots/a.svg"), b"x").unwrap_err();
        assert!(err.to_string().contains("symbolic link"), "{err}");
        assert_eq!(std::fs::read_dir(&elsewhere).unwrap().count(), 0);
        std::fs::write(elsewhere.join("target.txt"), b"keep").unwrap();
        std::os::unix::fs::symlink(elsewhere.join("target.txt"), root.join("summary.json")).unwrap();
        write_under(&root, Path::new("summary.json"), b"new").unwrap();
        assert_eq!(std::fs::read(elsewhere.join("target.txt")).unwrap(), b"keep");
        assert_eq!(std::fs::read(root.join("summary.json")).unwrap(), b"new");
    }
}
