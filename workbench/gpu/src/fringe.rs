//! The fringe shader's data on the GPU: the ghosts' [`FringeTable`]s packed into one storage
//! buffer ([`pack_tables`]) for `shaders/fringe.wgsl` ([`SHADER`]), the WGSL port of
//! `flarebench_sdk::ghost::fringe::FringeShader::shade`.

use flarebench_sdk::aperture::Aperture;
use flarebench_sdk::ghost::fringe_table::FringeTable;

use crate::uniforms::ApertureBlock;

/// The fringe shader's WGSL: `fn fringe_shade(a: array<f32, 12>) -> vec3<f32>` and its
/// helpers (all named `fringe_…`), reading [`pack_tables`]'s buffer at
/// `@group(1) @binding(0)`; no entry point, to be concatenated into a module that has one,
/// after [`APERTURE_SHADER`] (triangles flagged `APERTURE_FLAG` call it).
pub const SHADER: &str = include_str!("shaders/fringe.wgsl");

/// The aperture's WGSL (`aperture_soft`, `aperture_uniform_around` and their helpers), reading
/// its block at `@group(0) @binding(4)` and a mask's fields at `@group(0) @binding(5)`
/// ([`aperture_bindings`]).
pub const APERTURE_SHADER: &str = include_str!("shaders/aperture.wgsl");

/// What [`APERTURE_SHADER`] binds for `aperture`: its uniform block's bytes, and the mask's
/// transmission then distance field (a single 0 without a mask).
pub fn aperture_bindings(aperture: &Aperture) -> (Vec<u8>, Vec<f32>) {
    let block = ApertureBlock::new(aperture);
    let fields = match aperture {
        Aperture::Mask(mask) => [mask.data(), mask.distance_field()].concat(),
        _ => vec![0.0],
    };
    (bytemuck::bytes_of(&block).to_vec(), fields)
}

/// Intervals between a table's nodes, as `fringe.wgsl` has them (`FRINGE_NODES`).
pub const NODES: usize = 64;

/// f32s per packed table (`FRINGE_TABLE_STRIDE` in `fringe.wgsl`): `NODES + 1` nodes of 6.
pub const TABLE_STRIDE: usize = 6 * (NODES + 1);

/// The storage buffer `fringe.wgsl` reads (`fringe_data`): table `k` (the index a fringed
/// triangle's attribute 11 holds) at `k * TABLE_STRIDE`, its node `i` (`τ = i / NODES`) at
/// `+ 6 i` as `[F_r, F_g, F_b, H_r, H_g, H_b]` — the colour's share below `τ` and its integral
/// (`FringeTable::nodes`). With no table, a single 0 (a binding cannot be empty).
pub fn pack_tables(tables: &[FringeTable]) -> Vec<f32> {
    assert_eq!(
        FringeTable::NODE_COUNT,
        NODES,
        "fringe.wgsl's FRINGE_NODES must match the sdk's table"
    );
    let mut data = Vec::with_capacity((tables.len() * TABLE_STRIDE).max(1));
    for table in tables {
        let nodes = table.nodes();
        debug_assert_eq!(nodes.len(), NODES + 1);
        data.extend(nodes.iter().flatten());
    }
    if data.is_empty() {
        data.push(0.0);
    }
    data
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tables_pack_at_their_stride() {
        assert_eq!(pack_tables(&[]), vec![0.0]);
        let a = FringeTable::new(
            &[[0.0, 0.6], [0.4, 1.0]],
            &[[1.0, 0.5, 0.2], [0.3, 0.5, 1.0]],
        )
        .unwrap();
        let b = FringeTable::new(&[[0.0, 1.0]], &[[1.0; 3]]).unwrap();
        let data = pack_tables(&[a.clone(), b.clone()]);
        assert_eq!(data.len(), 2 * TABLE_STRIDE);
        assert_eq!(data[6 * 10..6 * 11], a.nodes()[10]);
        assert_eq!(data[TABLE_STRIDE + 6 * NODES..][..6], b.nodes()[NODES]);
        assert!(SHADER.contains(&format!("FRINGE_TABLE_STRIDE: u32 = {TABLE_STRIDE}u;")));
        assert!(SHADER.contains(&format!("FRINGE_NODES: u32 = {NODES}u;")));
    }
}
