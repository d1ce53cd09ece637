//! File operations of the editor: opening a lens, atomic saves, the recovery file beside the
//! lens (`.NAME.xml.recover`), and running an `Effect` to get the action that reports it.

use std::path::{Path, PathBuf};

use flarebench_sdk::LensSystem;
use flarebench_sdk::io::{parse_olf_xml, read_lens, save_xml, write_atomically, write_xml};

use super::action::{Action, Effect, Opened};
use crate::lens_library;

/// The recovery file of a lens saved at `path`: `.NAME.xml.recover` in the same directory.
pub fn recovery_path(path: &Path) -> PathBuf {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "untitled.xml".into());
    path.with_file_name(format!(".{name}.recover"))
}

/// Opens `spec` (a path or a bundled lens name). With `untitled`, the lens is a starting
/// point: saves ask for a path and the recovery file goes in the current directory.
pub fn open(spec: &str, untitled: bool) -> Result<Opened, String> {
    let source = lens_library::resolve(spec).map_err(|e| format!("{e:#}"))?;
    let loaded = read_lens(&source).map_err(|e| e.to_string())?;
    let is_xml = source
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("xml"));
    let stem = source
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "untitled".into());
    let (path, target) = if untitled {
        (None, PathBuf::from(format!("{stem}.xml")))
    } else if is_xml {
        (Some(source.clone()), source.clone())
    } else {
        // Not our format: saving goes to NAME.xml beside it, after asking.
        (None, source.with_extension("xml"))
    };
    let recovery_path = recovery_path(&target);
    let recovered = read_recovery(&recovery_path)?.filter(|r| *r != loaded.system);
    Ok(Opened {
        path,
        label: source.display().to_string(),
        system: loaded.system,
        recovery_path,
        recovered,
        warnings: loaded.warnings,
    })
}

/// The system in a recovery file; `None` when there is none.
fn read_recovery(path: &Path) -> Result<Option<LensSystem>, String> {
    let text = match std::fs::read_to_string(path) {
        Ok(t) => t,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
        Err(e) => return Err(format!("{}: {e}", path.display())),
    };
    parse_olf_xml(&text, &path.display().to_string())
        .map(|l| Some(l.system))
        .map_err(|e| format!("recovery file unreadable: {e}"))
}

/// Writes the recovery file for `system` (atomically).
pub fn write_recovery(path: &Path, system: &LensSystem) -> std::io::Result<()> {
    write_atomically(path, write_xml(system).as_bytes())
}

/// Runs `effect`; returns the action reporting its result (`None` for effects nobody waits
/// for, and for `Quit` and `OpenWindow`, which the runner handles).
pub fn perform(effect: &Effect) -> Option<Action> {
    match effect {
        Effect::Save {
            path,
            system,
            recovery,
        } => {
            let result = save_xml(system, path)
                .map_err(|e| format!("could not save {}: {e}", path.display()))
                .map(|()| {
                    let _ = std::fs::remove_file(recovery);
                    path.clone()
                });
            Some(Action::Saved(result))
        }
        Effect::WriteRecovery { path, system } => write_recovery(path, system)
            .err()
            .map(|e| Action::Failed(format!("recovery file {}: {e}", path.display()))),
        Effect::RemoveRecovery(path) => {
            let _ = std::fs::remove_file(path);
            None
        }
        Effect::Open(spec) => Some(Action::Opened(open(spec, false).map(Box::new))),
        Effect::Quit | Effect::OpenWindow => None,
    }
}
