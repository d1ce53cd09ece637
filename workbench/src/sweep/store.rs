//! The sweep directory's cache: each finished cell as `cells/<hash>.json` beside its thumbnail
//! `cells/<hash>.exr`, each reference as `references/<hash>.exr` beside its ghost-by-ghost
//! record `references/<hash>.json`. The hash is of a key naming everything the result depends
//! on, and the key is stored inside the file too: a file whose key differs is not used. The
//! JSON is written last, atomically, so a file there means a finished result.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use flarebench_sdk::hash::fnv1a_hex;
use flarebench_sdk::image::HdrImage;
use flarebench_sdk::io::write_atomically;

use super::{CellResult, ReferenceRecord};
use crate::output::{encode_exr, read_exr};

#[derive(Debug)]
pub struct Store {
    root: PathBuf,
}

impl Store {
    /// The store in sweep directory `root` (created with its subdirectories).
    pub fn open(root: &Path) -> Result<Store> {
        for d in ["cells", "references"] {
            let p = root.join(d);
            std::fs::create_dir_all(&p).with_context(|| format!("creating {}", p.display()))?;
        }
        Ok(Store {
            root: root.to_path_buf(),
        })
    }

    pub fn root(&self) -> &Path {
        &self.root
    }

    /// The cell's thumbnail, relative to the sweep directory.
    pub fn cell_thumbnail(key: &str) -> String {
        format!("cells/{}.exr", fnv1a_hex(key.as_bytes()))
    }

    /// The reference's thumbnail, relative to the sweep directory.
    pub fn reference_thumbnail(key: &str) -> String {
        format!("references/{}-thumb.exr", fnv1a_hex(key.as_bytes()))
    }

    fn cell_json(&self, key: &str) -> PathBuf {
        self.root
            .join(format!("cells/{}.json", fnv1a_hex(key.as_bytes())))
    }

    fn reference_stem(&self, key: &str) -> PathBuf {
        self.root
            .join(format!("references/{}", fnv1a_hex(key.as_bytes())))
    }

    /// A finished cell of this key, if the directory holds one.
    pub fn load_cell(&self, key: &str) -> Option<CellResult> {
        let text = std::fs::read_to_string(self.cell_json(key)).ok()?;
        serde_json::from_str::<CellResult>(&text)
            .ok()
            .filter(|c| c.key == key)
    }

    /// Writes a finished cell and its thumbnail.
    pub fn save_cell(&self, cell: &CellResult, thumbnail: Option<&HdrImage>) -> Result<()> {
        if let Some(t) = thumbnail {
            self.write(
                &self.root.join(Self::cell_thumbnail(&cell.key)),
                &encode_exr(t)?,
            )?;
        }
        self.write(
            &self.cell_json(&cell.key),
            &serde_json::to_vec_pretty(cell)?,
        )
    }

    /// A reference of this key and its image, if the directory holds them.
    pub fn load_reference(&self, key: &str) -> Option<(ReferenceRecord, HdrImage)> {
        let stem = self.reference_stem(key);
        let text = std::fs::read_to_string(stem.with_extension("json")).ok()?;
        let rec = serde_json::from_str::<ReferenceRecord>(&text)
            .ok()
            .filter(|r| r.key == key)?;
        let img = read_exr(&stem.with_extension("exr")).ok()?;
        Some((rec, img))
    }

    /// Writes a reference, its image and its thumbnail.
    pub fn save_reference(
        &self,
        rec: &ReferenceRecord,
        img: &HdrImage,
        thumbnail: &HdrImage,
    ) -> Result<()> {
        let stem = self.reference_stem(&rec.key);
        self.write(&stem.with_extension("exr"), &encode_exr(img)?)?;
        self.write(
            &self.root.join(Self::reference_thumbnail(&rec.key)),
            &encode_exr(thumbnail)?,
        )?;
        self.write(
            &stem.with_extension("json"),
            &serde_json::to_vec_pretty(rec)?,
        )
    }

    /// A thumbnail by its path relative to the sweep directory.
    pub fn read_thumbnail(&self, rel: &str) -> Option<HdrImage> {
        read_exr(&self.root.join(rel)).ok()
    }

    fn write(&self, path: &Path, bytes: &[u8]) -> Result<()> {
        write_atomically(path, bytes).with_context(|| format!("writing {}", path.display()))
    }
}
