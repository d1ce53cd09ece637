//! The lens fingerprint: what precomputed tables and cached references are keyed by, so a file
//! made for another lens (or an edited one) is told apart. Its own module above `io` (it hashes
//! the canonical XML `io` writes), so `ghost` reads files through `io` but never writes them.

use crate::system::LensSystem;

/// FNV-1a (64 bit) of the lens's canonical XML, as hex.
pub fn fingerprint(system: &LensSystem) -> String {
    crate::hash::fnv1a_hex(crate::io::write_xml(system).as_bytes())
}
