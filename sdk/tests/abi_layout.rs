//! The plugin ABI's layout (sizes, alignments, field offsets of every `#[repr(C)]` type in
//! `sdk::abi::v1`) against a committed snapshot: an accidental ABI change fails here. An
//! intended one appends fields (minor version) or bumps `ABI_MAJOR`, and updates the snapshot
//! (`cargo insta review`).

use flarebench_sdk::abi::v1;

#[test]
fn abi_v1_layout_matches_the_snapshot() {
    insta::assert_snapshot!("abi_v1_layout", v1::layout::describe());
}

#[test]
fn the_header_prefix_is_the_same_twenty_bytes_in_every_version() {
    // The host reads these four fields before knowing the plugin's ABI version.
    assert_eq!(std::mem::offset_of!(v1::PluginHeader, magic), 0);
    assert_eq!(std::mem::offset_of!(v1::PluginHeader, abi_major), 8);
    assert_eq!(std::mem::offset_of!(v1::PluginHeader, abi_minor), 12);
    assert_eq!(std::mem::offset_of!(v1::PluginHeader, struct_size), 16);
}
