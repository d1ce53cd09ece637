//! Saved reference images: the reference renderer takes minutes on large frames, so `render`
//! and `compare` can keep its image in an OpenEXR file (`--reference-file FILE`) and reuse it
//! while the scene stays the same. The file carries the scene's key
//! ([`ghost_raytrace::reference::reference_key`]: renderer version, lens fingerprint,
//! aperture, frame, lights) as the text attribute [`KEY_ATTRIBUTE`]; a file made for another
//! scene is refused, never silently used.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use flarebench_sdk::LensSystem;
use flarebench_sdk::aperture::Aperture;
use flarebench_sdk::frame::Frame;
use flarebench_sdk::ghost::ReflectionOrder;
use flarebench_sdk::image::HdrImage;
use flarebench_sdk::io::write_atomically;
use ghost_raytrace::reference::{reference_image_of_order, reference_key};
use ghost_raytrace::scene::LightSpec;

use crate::output::{encode_exr_with, read_exr_with_attributes};

/// The EXR text attribute holding the scene's key.
pub const KEY_ATTRIBUTE: &str = "flarebench-reference-key";

/// Where a reference image came from.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum ReferenceSource {
    /// Rendered now and not saved.
    Rendered,
    /// Rendered now and written to this file.
    Saved(PathBuf),
    /// Read from this file, made earlier for the same scene.
    Read(PathBuf),
}

impl std::fmt::Display for ReferenceSource {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            ReferenceSource::Rendered => write!(f, "rendered"),
            ReferenceSource::Saved(p) => write!(f, "rendered and saved to {}", p.display()),
            ReferenceSource::Read(p) => write!(f, "read from {}", p.display()),
        }
    }
}

/// The reference image of the scene (its ghosts of `reflections`): read from `file` when it exists (and was made for this
/// scene — else an error naming both keys), otherwise rendered and, with `file`, written
/// there.
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
    let img = reference_image_of_order(system, aperture, frame, lights, reflections)?;
    let Some(path) = file else {
        return Ok((img, ReferenceSource::Rendered));
    };
    let bytes = encode_exr_with(&img, &[(KEY_ATTRIBUTE, &key)])?;
    write_atomically(path, &bytes)
        .with_context(|| format!("could not write the reference to `{}`", path.display()))?;
    Ok((img, ReferenceSource::Saved(path.to_path_buf())))
}
