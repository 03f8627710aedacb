//! A `--plot` path checked before a run, so that a plot that cannot be
//! written is refused at once, not after the run.

use std::path::Path;

/// `Ok` when `path` ends in `.svg` or `.png` and its folder exists.
pub fn check(path: &Path) -> Result<(), String> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    if !matches!(ext.as_deref(), Some("svg" | "png")) {
        return Err(format!(
            "--plot {}: the plot is written as .svg or .png",
            path.display()
        ));
    }
    let folder = path.parent().filter(|p| !p.as_os_str().is_empty());
    if folder.is_some_and(|f| !f.is_dir()) {
        return Err(format!("--plot {}: no such folder", path.display()));
    }
    Ok(())
}
