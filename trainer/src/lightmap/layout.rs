//! Which UVs a light map lies on: the character's texture UVs, laid out for painting, or a
//! light-map atlas generated for lighting ([`crate::rig::uv::generate`]), which the `.shlm`
//! file (and a light-map model's texel atlas) stores so readers sample where the bake baked.

use anyhow::{Result, bail};

use crate::rig::Rig;
use crate::rig::uv::UvLayout;
use crate::rig::uv::generate::{
    DEFAULT_HARD_ANGLE_DEG, DEFAULT_MARGIN_TEXELS, UnwrapSettings, generate_layout,
};

/// The UVs a light map is baked on.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LightMapUvs {
    /// The character's own texture UVs (glTF `TEXCOORD_0`, OBJ `vt`).
    Texture,
    /// A light-map atlas generated for the bind mesh.
    Generate {
        /// Faces folding by more than this many degrees are cut apart.
        hard_angle_deg: f32,
        /// Empty texels around each chart.
        margin_texels: u32,
    },
}

impl LightMapUvs {
    /// Generated UVs with the default hard angle and margin.
    pub const DEFAULT_GENERATE: LightMapUvs = LightMapUvs::Generate {
        hard_angle_deg: DEFAULT_HARD_ANGLE_DEG,
        margin_texels: DEFAULT_MARGIN_TEXELS,
    };
}

/// The atlas a light map is baked on: its size and which UVs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AtlasSpec {
    /// Atlas width and height in texels.
    pub resolution: usize,
    /// Which UVs.
    pub uvs: LightMapUvs,
}

/// The layout `uvs` names for `rig` (called `what` in errors) at `resolution`² texels, and
/// whether it must be stored with the maps (generated UVs are not the character's).
pub fn layout_for(
    rig: &dyn Rig,
    what: &str,
    uvs: LightMapUvs,
    resolution: usize,
) -> Result<(UvLayout, bool)> {
    match uvs {
        LightMapUvs::Texture => Ok((texture_layout(rig, what)?.clone(), false)),
        LightMapUvs::Generate {
            hard_angle_deg,
            margin_texels,
        } => {
            let settings = UnwrapSettings {
                resolution,
                hard_angle_deg,
                margin_texels,
            };
            let layout =
                generate_layout(rig.bind_mesh(), rig.uv_layout(), &settings).map_err(|e| {
                    anyhow::anyhow!(
                        "{what}: generating light-map UVs at {resolution}x{resolution}: {e}"
                    )
                })?;
            Ok((layout, true))
        }
    }
}

/// The rig's texture UV layout, or the error that says the character has none or why a light
/// map cannot lie on it: a corner outside `[0, 1]²` (the atlas does not wrap repeating
/// textures) or a triangle whose UVs have no area though it has. No texel stands for such a
/// surface, so its vertices would read no transfer (a bake went through, and read 11.7 % and
/// 18.8 % error against 2.55 %).
pub fn texture_layout<'r>(rig: &'r dyn Rig, what: &str) -> Result<&'r UvLayout> {
    let fix = "bake its light map on generated UVs (--uv generate, the default)";
    let Some(layout) = rig.uv_layout() else {
        bail!("{what} has no texture coordinates (glTF TEXCOORD_0, OBJ vt): {fix}");
    };
    if let Some((t, k, _)) = layout.outside_unit_square() {
        let [u, v] = layout.corners[t][k];
        bail!(
            "{what}: corner {k} of triangle {t} has texture UV ({u}, {v}) (v down, as glTF's), outside [0, 1]² (a light map does not wrap repeating textures): {fix}"
        );
    }
    if let Some(t) = layout.first_flat_triangle(rig.bind_mesh()) {
        bail!(
            "{what}: the texture UVs of triangle {t} have no area though the triangle has: no texel would stand for its surface; {fix}"
        );
    }
    Ok(layout)
}

/// The character's texture UVs, which the maps read back from a file (called `name`) lie on
/// when it stores no UVs of its own. A character without them is refused naming the file too:
/// its missing UVs send the reader to the character's ("the character has no texture
/// coordinates" alone blamed the character for a file stripped of its UVs).
pub fn texture_of_file<'r>(rig: &'r dyn Rig, name: &str) -> Result<&'r UvLayout> {
    if rig.uv_layout().is_none() {
        bail!(
            "{name} stores no light-map UVs, so its maps lie on the character's texture UVs, and the character has none (glTF TEXCOORD_0, OBJ vt): give the character it was baked from"
        );
    }
    texture_layout(rig, "the character")
}

/// The layout maps read back from a file (called `name`) lie on: the UVs it stores, which
/// must have one entry per triangle of `rig`'s bind mesh, or else the character's texture UVs.
pub fn stored_or_texture(stored: Option<&UvLayout>, rig: &dyn Rig, name: &str) -> Result<UvLayout> {
    let triangles = rig.bind_mesh().triangles.len();
    match stored {
        Some(layout) if layout.corners.len() == triangles => Ok(layout.clone()),
        Some(layout) => bail!(
            "{name} stores light-map UVs for {} triangles, the character has {triangles}: give the character the light map was baked from",
            layout.corners.len()
        ),
        None => Ok(texture_of_file(rig, name)?.clone()),
    }
}
