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

#[test]
fn a_1_0_scene_is_the_first_64_bytes_of_every_1_x_scene() {
    // A 1.1 plugin reads a 1.0 host's scene up to here and no further.
    assert_eq!(v1::SceneInput::SIZE_1_0, 64);
    assert_eq!(std::mem::offset_of!(v1::SceneInput, aperture), 40);
    assert_eq!(size_of::<v1::ApertureInput>(), 24);
}
