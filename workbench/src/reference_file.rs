//! Saved reference images: the reference renderer takes minutes on large frames, so `render`
//! and `compare` can keep its image in an OpenEXR file (`--reference-file FILE`) and reuse it
//! while the scene stays the same. The file carries the scene's key
//! ([`ghost_raytrace::reference::reference_key`]: renderer version, lens fingerprint,
//! aperture, frame, lights) as the text attribute [`KEY_ATTRIBUTE`]; a file made for another
//! scene is refused, never silently used.
//!
//! Without a file, a reference is kept in the cache directory ([`cache_dir`]: by default
//! `$XDG_CACHE_HOME/flarebench/references`, or `~/.cache/…`; [`CACHE_ENV`] names another, or,
//! set empty, turns it off), one file per scene named by the FNV-1a hash of its key, and read
//! back while the scene stays the same: the second `render --reference` or `compare` of a
//! scene does not render the reference again. A reference rendered for a `--reference-file`
//! is kept in the cache too, and a `--reference-file` that does not exist yet is written from
//! the cache when it holds the scene. A cached file that cannot be read or holds
//! another key is rendered over; a cache that cannot be written is passed over with a
//! warning.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use flarebench_sdk::LensSystem;
use flarebench_sdk::aperture::Aperture;
use flarebench_sdk::frame::Frame;
use flarebench_sdk::ghost::ReflectionOrder;
use flarebench_sdk::hash::fnv1a_hex;
use flarebench_sdk::image::HdrImage;
use flarebench_sdk::io::write_atomically;
use ghost_raytrace::reference::{reference_image_of_order, reference_key};
use ghost_raytrace::scene::LightSpec;

use crate::output::{encode_exr_with, read_exr_with_attributes};

/// The EXR text attribute holding the scene's key.
pub const KEY_ATTRIBUTE: &str = "flarebench-reference-key";

/// The environment variable naming the reference cache's directory (empty: no cache).
pub const CACHE_ENV: &str = "FLAREBENCH_REFERENCE_CACHE";

/// The reference cache's directory: [`CACHE_ENV`] if set (`None` when empty), else
/// `$XDG_CACHE_HOME/flarebench/references`, else `$HOME/.cache/flarebench/references`.
pub fn cache_dir() -> Option<PathBuf> {
    if let Some(d) = std::env::var_os(CACHE_ENV) {
        return (!d.is_empty()).then(|| PathBuf::from(d));
    }
    let base = std::env::var_os("XDG_CACHE_HOME")
        .filter(|d| !d.is_empty())
        .map(PathBuf::from)
        .or_else(|| std::env::var_os("HOME").map(|h| Path::new(&h).join(".cache")))?;
    Some(base.join("flarebench").join("references"))
}

/// The cache's file for the scene of `key`, when there is a cache.
fn cache_file(key: &str) -> Option<PathBuf> {
    cache_dir().map(|d| d.join(format!("{}.exr", fnv1a_hex(key.as_bytes()))))
}

/// True when the cache holds a file for this scene (whether it is still good is checked when
/// it is read): callers say "rendering the reference" only when it is not.
pub fn in_cache(
    system: &LensSystem,
    aperture: &Aperture,
    frame: Frame,
    lights: &[LightSpec],
    reflections: ReflectionOrder,
) -> bool {
    cache_file(&reference_key(
        system,
        aperture,
        &frame,
        lights,
        reflections,
    ))
    .is_some_and(|p| p.is_file())
}

/// Where a reference image came from.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum ReferenceSource {
    /// Rendered now and not saved.
    Rendered,
    /// Rendered now and written to this file.
    Saved(PathBuf),
    /// Read from this file, made earlier for the same scene.
    Read(PathBuf),
    /// Read from this file of the cache ([`cache_dir`]).
    Cached(PathBuf),
    /// Read from the cache and written to the `--reference-file` that did not exist yet.
    CachedSaved { cache: PathBuf, file: PathBuf },
    /// Rendered now and kept in this file of the cache.
    CachedNow(PathBuf),
}

impl std::fmt::Display for ReferenceSource {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            ReferenceSource::Rendered => write!(f, "rendered"),
            ReferenceSource::Saved(p) => write!(f, "rendered and saved to {}", p.display()),
            ReferenceSource::Read(p) => write!(f, "read from {}", p.display()),
            ReferenceSource::Cached(p) => write!(f, "read from the cache ({})", p.display()),
            ReferenceSource::CachedSaved { cache, file } => write!(
                f,
                "read from the cache ({}) and saved to {}",
                cache.display(),
                file.display()
            ),
            ReferenceSource::CachedNow(p) => write!(f, "rendered and cached ({})", p.display()),
        }
    }
}

/// The reference image of the scene (its ghosts of `reflections`): read from `file` when it
/// exists (and was made for this scene — else an error naming both keys); otherwise read from
/// the cache when it holds this scene, else rendered and kept there ([`cache_dir`]; the
/// module's docs), and, with `file`, written to `file` as well.
pub fn reference_for(
    system: &LensSystem,
    aperture: &Aperture,
    frame: Frame,
    lights: &[LightSpec],
    file: Option<&Path>,
    reflections: ReflectionOrder,
) -> Result<(HdrImage, ReferenceSource)> {
    let key = reference_key(system, aperture, &frame, lights, reflections);
    if let Some(path) = file.filter(|p| p.exists()) {
        let (img, text) = read_exr_with_attributes(path)?;
        match text.get(KEY_ATTRIBUTE) {
            Some(k) if *k == key => {}
            Some(k) => bail!(
                "`{}` holds the reference of another scene:\n  file: {k}\n  this: {key}\n\
                 delete it or pass another --reference-file",
                path.display()
            ),
            None => bail!(
                "`{}` is not a saved reference (it has no `{KEY_ATTRIBUTE}` attribute); \
                 delete it or pass another --reference-file",
                path.display()
            ),
        }
        if (img.width, img.height) != (frame.width, frame.height) {
            bail!(
                "`{}` is {}×{}, not the frame's {}×{}",
                path.display(),
                img.width,
                img.height,
                frame.width,
                frame.height
            );
        }
        return Ok((img, ReferenceSource::Read(path.to_path_buf())));
    }
    let cached = cache_file(&key);
    if let Some(cache) = &cached
        && let Ok((img, text)) = read_exr_with_attributes(cache)
        && text.get(KEY_ATTRIBUTE) == Some(&key)
        && (img.width, img.height) == (frame.width, frame.height)
    {
        let Some(path) = file else {
            return Ok((img, ReferenceSource::Cached(cache.clone())));
        };
        save(&img, &key, path)?;
        return Ok((
            img,
            ReferenceSource::CachedSaved {
                cache: cache.clone(),
                file: path.to_path_buf(),
            },
        ));
    }
    let img = reference_image_of_order(system, aperture, frame, lights, reflections)?;
    let kept = cached.and_then(|cache| {
        let bytes = encode_exr_with(&img, &[(KEY_ATTRIBUTE, &key)]).and_then(|bytes| {
            if let Some(dir) = cache.parent() {
                std::fs::create_dir_all(dir)?;
            }
            Ok(write_atomically(&cache, &bytes)?)
        });
        match bytes {
            Ok(()) => Some(cache),
            Err(e) => {
                eprintln!(
                    "warning: could not keep the reference in the cache `{}` ({e:#}); set {CACHE_ENV} to another directory, or empty to turn the cache off",
                    cache.display()
                );
                None
            }
        }
    });
    let source = match (file, kept) {
        (Some(path), _) => {
            save(&img, &key, path)?;
            ReferenceSource::Saved(path.to_path_buf())
        }
        (None, Some(cache)) => ReferenceSource::CachedNow(cache),
        (None, None) => ReferenceSource::Rendered,
    };
    Ok((img, source))
}

/// Writes a reference image with its scene's key to `path` (`--reference-file`).
fn save(img: &HdrImage, key: &str, path: &Path) -> Result<()> {
    let bytes = encode_exr_with(img, &[(KEY_ATTRIBUTE, key)])?;
    write_atomically(path, &bytes)
        .with_context(|| format!("could not write the reference to `{}`", path.display()))
}
