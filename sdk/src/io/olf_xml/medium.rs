//! The medium after a surface: a catalogue `<glass>`, or `refractiveIndex` and `abbeNumber`.

use super::fields::{Ctx, Fields, number};
use crate::glass::GlassCatalog;
use crate::io::LensFileError;
use crate::io::xml_tree::Node;
use crate::system::Medium;

/// The Abbe number: a finite value, or `inf` for a non-dispersive medium.
enum Abbe {
    Finite(f64),
    NonDispersive,
}

fn read_abbe(ctx: &mut Ctx<'_>, node: Option<&Node>) -> Result<Option<Abbe>, LensFileError> {
    if let Some(n) = node
        && let Ok(v) = n.value().parse::<f64>()
        && v == f64::INFINITY
    {
        return Ok(Some(Abbe::NonDispersive));
    }
    Ok(number(ctx, node)?.map(Abbe::Finite))
}

/// The medium after the surface: a catalogue `<glass>`, else `refractiveIndex`/`abbeNumber`.
pub(super) fn read_medium(
    ctx: &mut Ctx<'_>,
    f: &Fields<'_>,
    node: &Node,
    lens: bool,
) -> Result<Medium, LensFileError> {
    let nd = number(ctx, f.get("refractiveIndex"))?;
    let abbe = read_abbe(ctx, f.get("abbeNumber"))?;
    if let Some(g) = f.get("glass") {
        let name = g.value();
        if name.is_empty() {
            ctx.warn(g.pos, "<glass> is empty; treated as absent");
        } else {
            let entry = GlassCatalog::bundled()
                .find(name)
                .map_err(|e| ctx.error(g.value_pos(), "glass", e.to_string()))?;
            if let Some(n) = nd
                && (n - entry.nd).abs() > 5e-5
            {
                ctx.warn(
                    g.value_pos(),
                    format!(
                        "refractiveIndex {n} differs from {}'s nd {}; the glass is used",
                        entry.canonical_name(),
                        entry.nd
                    ),
                );
            }
            if let Some(Abbe::Finite(v)) = abbe
                && (v - entry.vd).abs() > 0.05
            {
                ctx.warn(
                    g.value_pos(),
                    format!(
                        "abbeNumber {v} differs from {}'s Vd {}; the glass is used",
                        entry.canonical_name(),
                        entry.vd
                    ),
                );
            }
            return Ok(Medium::Glass {
                name: entry.canonical_name(),
                dispersion: entry.dispersion.clone(),
            });
        }
    }
    Ok(match nd {
        None => {
            if lens {
                ctx.warn(
                    node.pos,
                    "no <refractiveIndex>; the medium after this surface is taken as air",
                );
            }
            Medium::Air
        }
        Some(1.0) => Medium::Air,
        Some(n) => {
            let vd = match abbe {
                Some(Abbe::Finite(v)) => Some(v),
                Some(Abbe::NonDispersive) => None,
                None => {
                    ctx.warn(
                        node.pos,
                        format!(
                            "glass n = {n} without <abbeNumber> is taken as non-dispersive \
                             (write <abbeNumber>inf</abbeNumber> to say so)"
                        ),
                    );
                    None
                }
            };
            Medium::Model { nd: n, vd }
        }
    })
}
