//! An element's coating: `<coatingStack>`, else OpenLensFlare's single layer.

use super::fields::{Ctx, Fields, number};
use super::tags;
use crate::coating::{Coating, CoatingLayer};
use crate::io::LensFileError;
use crate::io::xml_tree::Node;

/// `<coatingStack>` takes precedence; else `coatingLambda` + `coatingIor` (0 or absent: none).
pub(super) fn read_coating(ctx: &mut Ctx<'_>, f: &Fields<'_>) -> Result<Coating, LensFileError> {
    if let Some(stack) = f.get("coatingStack") {
        let mut layers = Vec::new();
        for child in &stack.children {
            if child.name != tags::LAYER {
                ctx.warn(
                    child.pos,
                    format!("unknown tag <{}> in <coatingStack> ignored", child.name),
                );
                continue;
            }
            let lf = Fields::collect(ctx, child, tags::LAYER_TAGS);
            let mut value = |tag: &str| -> Result<f64, LensFileError> {
                number(ctx, lf.get(tag))?.ok_or_else(|| {
                    ctx.error(child.pos, tag, format!("a coating layer needs <{tag}>"))
                })
            };
            let index = value("index")?;
            let thickness_nm = value("thicknessNm")?;
            layers.push(CoatingLayer {
                index,
                thickness_nm,
            });
        }
        return Ok(Coating::Stack(layers));
    }
    let lambda = number(ctx, f.get("coatingLambda"))?.unwrap_or(0.0);
    let ior = number(ctx, f.get("coatingIor"))?.unwrap_or(0.0);
    Ok(if lambda != 0.0 && ior != 0.0 {
        Coating::SingleLayer {
            design_wavelength_nm: lambda,
            index: ior,
        }
    } else {
        if lambda != 0.0 || ior != 0.0 {
            let at = f
                .get("coatingIor")
                .or(f.get("coatingLambda"))
                .map_or(0, Node::value_pos);
            ctx.warn(
                at,
                "a coating needs both coatingLambda and coatingIor; the surface is uncoated",
            );
        }
        Coating::None
    })
}
