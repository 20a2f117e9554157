//! The two ways to hold a model: [`Model`] over a resident blob, read in place, and
//! [`StreamedModel`] over any [`BlobSource`], read through a caller's buffer. Both validate
//! the whole blob once and share one evaluator; their per-frame calls take the same
//! arguments in the same order (inputs, then the first vertex, then the output).

use crate::blob::{
    AngleNames, BlobSource, Error, ModelInfo, Reader, Resident, Streaming, TexelAtlas,
};
use crate::eval::{LitWeights, PoseWeights, VertexRows};
use crate::irradiance_rig::{IrradianceRig, Placement, RigLitWeights};
use crate::light::Light;
use crate::proxies::{ProxyFrame, Skinning};
use crate::rotation::Rotation;

/// A model whose blob is in memory: every call reads it in place, with no buffer.
///
/// `Model` is `Copy` and its calls take `&self`, so threads may shade disjoint vertex ranges
/// of one model at once, each with its own output.
///
/// ```
/// # fn main() -> Result<(), aprt_core::Error> {
/// use aprt_core::{LitWeights, Model, PoseWeights};
///
/// let blob: &[u8] = include_bytes!("../../fixtures/golden/v1-world.aprt");
/// let model = Model::parse(blob)?;
/// let info = model.info();
/// let (mut pose, mut lit) = (PoseWeights::new(), LitWeights::new());
/// model.set_pose(&vec![0.1; info.pose_len()], &mut pose)?;
/// model.light(&pose, &vec![1.0; info.coeffs()], &[], &mut lit)?;
/// let mut shading = vec![0.0; info.vertices()];
/// model.shade(&lit, 0, &mut shading)?;
/// # Ok(())
/// # }
/// ```
#[derive(Clone, Copy, PartialEq)]
pub struct Model<'a> {
    blob: &'a [u8],
    info: ModelInfo,
    rig: Option<IrradianceRig<'a>>,
    atlas: Option<TexelAtlas<'a>>,
}

impl<'a> Model<'a> {
    /// Validates a resident blob completely, once: header, dimensions, section table,
    /// checksums, finiteness of every value, bone indices and angle names.
    ///
    /// ```
    /// use aprt_core::{Error, Model};
    ///
    /// let blob = include_bytes!("../../fixtures/golden/v1-world.aprt");
    /// assert_eq!(Model::parse(blob)?.info().order(), 3);
    /// assert_eq!(Model::parse(&blob[..10]), Err(Error::Truncated { needed: 20 }));
    /// # Ok::<(), Error>(())
    /// ```
    pub fn parse(blob: &'a [u8]) -> Result<Model<'a>, Error> {
        let info = ModelInfo::open(&mut Resident(blob))?;
        let rig = match info.irradiance_rig {
            // `open` checked that the span lies inside the blob.
            Some(span) => Some(IrradianceRig::parse(
                &blob[span.offset as usize..(span.offset + span.len) as usize],
            )?),
            None => None,
        };
        let atlas = match info.texel_atlas {
            Some(span) => Some(TexelAtlas::parse(
                &blob[span.offset as usize..(span.offset + span.len) as usize],
                info.vertices,
            )?),
            None => None,
        };
        Ok(Model {
            blob,
            info,
            rig,
            atlas,
        })
    }

    /// The irradiance rig fitted to the character, when the model has one (validated by
    /// [`Model::parse`]).
    pub fn irradiance_rig(&self) -> Option<IrradianceRig<'a>> {
        self.rig
    }

    /// The texel of every row, when the model is a light-map model that records its atlas
    /// (validated by [`Model::parse`]): [`TexelAtlas::scatter`] places the rows' shading in the
    /// R × R map.
    pub fn texel_atlas(&self) -> Option<TexelAtlas<'a>> {
        self.atlas
    }

    /// The model's dimensions and what its calls need.
    pub fn info(&self) -> &ModelInfo {
        &self.info
    }

    /// The blob it reads.
    pub fn blob(&self) -> &'a [u8] {
        self.blob
    }

    /// The per-vertex rows as stored, for a device that runs the per-vertex loops itself (a
    /// GPU): with [`ModelInfo::lit_values`] they give [`Model::shade`], with
    /// [`ModelInfo::transfer_weights`] [`Model::transfer`].
    pub fn vertex_rows(&self) -> VertexRows<'a> {
        self.info.vertex_rows(self.blob)
    }

    /// The names of the pose-vector entries, to bind an engine's joints by name (empty when
    /// the blob records none).
    ///
    /// ```
    /// let model = aprt_core::Model::parse(include_bytes!("../../fixtures/golden/v1-bones.aprt"))?;
    /// let names = model.angle_names();
    /// assert_eq!(names.len(), model.info().pose_len());
    /// assert_eq!(names.index_of("neck.y"), Some(1));
    /// # Ok::<(), aprt_core::Error>(())
    /// ```
    pub fn angle_names(&self) -> AngleNames<'a> {
        let Some(span) = self.info.angle_names else {
            return AngleNames::default();
        };
        // Validated by `parse`; the blob cannot have changed since (it is borrowed).
        self.blob
            .get(span.offset as usize..(span.offset + span.len) as usize)
            .and_then(|b| AngleNames::parse(b, self.info.pose_len).ok())
            .unwrap_or_default()
    }

    /// Computes the pose weights of one frame from the pose vector `angles`
    /// ([`ModelInfo::pose_len`] values): `z = P(φ(b(a)) − μ)`, then `w^c = W^c [1, z]`.
    ///
    /// `b` is the pose bound of a bounded model ([`ModelInfo::bounded`]), the identity
    /// otherwise: each entry is clamped into the range the training poses (and the prior's pose)
    /// spanned, and the pose is blended towards the prior's pose by `β = max(0, 1 − d)`, where
    /// `d` is the distance outside that box in units of its falloff. Inside the box a pose is
    /// unchanged; far outside it the model gives its prior (the rest transfer carried by the
    /// skin, or the mean transfer) instead of extrapolating without limit.
    ///
    /// `φ` gives the pose features ([`ModelInfo::feature_len`] values): the bounded angles,
    /// then `1 − cos a_i` for each entry the model flags, so the model can learn shadowing
    /// that is the same whichever way a joint turns. Without flags, `φ(a) = a`.
    ///
    /// # The pose vector
    /// Entry `i` is the value named by [`Model::angle_names`]`.get(i)`, exactly as the trainer
    /// computed it for the training clip:
    /// - For a character (glTF skin, BVH mannequin) the entries `<joint>.x/.y/.z` are the
    ///   joint's rotation vector relative to its rest pose: the log map (angle × unit axis,
    ///   radians) of `q_rest⁻¹ · q_local`, the joint's local rotation seen in its own rest
    ///   frame. The built-in character's entries are single named angles in radians.
    /// - Along a clip each joint's vector is unwrapped: of the equal rotations
    ///   `v̂ (|v| + 2πk)`, take the one nearest the same joint's vector in the previous frame
    ///   (the first frame takes `k = 0`, angle ≤ π). A joint that turns past a half turn
    ///   otherwise jumps to the other side.
    /// - Only the entries the model kept are passed (joints that never moved in training
    ///   were dropped); bind them by name once with [`AngleNames::index_of`].
    ///
    /// ```
    /// use aprt_core::{Error, Input, Model, PoseWeights};
    ///
    /// let model = Model::parse(include_bytes!("../../fixtures/golden/v1-world.aprt"))?;
    /// let mut pose = PoseWeights::new();
    /// model.set_pose(&[0.1, -0.2, 0.3, 0.0], &mut pose)?;
    /// assert_eq!(pose.projected().len(), model.info().pose_dims());
    /// assert_eq!(
    ///     model.set_pose(&[0.1], &mut pose),
    ///     Err(Error::WrongLength { what: Input::Angles, expected: 4, found: 1 })
    /// );
    /// # Ok::<(), Error>(())
    /// ```
    pub fn set_pose<const N: usize>(
        &self,
        angles: &[f32],
        pose: &mut PoseWeights<N>,
    ) -> Result<(), Error> {
        self.info.set_pose(&mut Resident(self.blob), angles, pose)
    }

    /// Pushes the world SH lighting `lighting` ([`ModelInfo::coeffs`] values) through the
    /// pose weights: `s_k = Σ_c L_c w^c_k`. Reads no blob bytes.
    ///
    /// `bones` holds the bones' rotations, which a bone-frame model needs (one per bone,
    /// [`ModelInfo::bones`]; it rotates the lighting into each bone's frame once per frame)
    /// and a world-frame model ignores, so an engine may always pass its skeleton's. Bone `b`'s rotation is
    /// the rotation part of its *skinning* matrix `world(b) · inverse_bind(b)`, row-major
    /// (not its world rotation); bone indices are the skin's joint order (glTF `skin.joints`).
    /// A skinning matrix with scale or shear must be reduced to its nearest rotation first
    /// (polar decomposition): a matrix more than 10⁻³ from orthonormal is refused.
    ///
    /// ```
    /// use aprt_core::{Error, Input, LitWeights, Model, PoseWeights};
    ///
    /// let model = Model::parse(include_bytes!("../../fixtures/golden/v1-bones.aprt"))?;
    /// let (mut pose, mut lit) = (PoseWeights::new(), LitWeights::new());
    /// model.set_pose(&[0.2; 5], &mut pose)?;
    /// let lighting = [1.0, 0.0, 0.5, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0];
    /// let identity = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    /// assert_eq!(
    ///     model.light(&pose, &lighting, &[], &mut lit),
    ///     Err(Error::WrongLength { what: Input::BoneRotations, expected: 3, found: 0 })
    /// );
    /// model.light(&pose, &lighting, &[identity; 3], &mut lit)?;
    /// # Ok::<(), Error>(())
    /// ```
    pub fn light<const P: usize, const L: usize>(
        &self,
        pose: &PoseWeights<P>,
        lighting: &[f32],
        bones: &[Rotation],
        lit: &mut LitWeights<L>,
    ) -> Result<(), Error> {
        self.info.light(pose, lighting, bones, lit)
    }

    /// Per-vertex shading `Σ_c L_c t_c(j)` of vertices `first .. first + out.len()`, from the
    /// lighting weights of [`Model::light`]. Multiply by albedo / π for exit radiance. Any
    /// range works; ranges starting at multiples of [`VERTEX_BLOCK`](crate::VERTEX_BLOCK) read
    /// no block twice.
    ///
    /// ```
    /// use aprt_core::{LitWeights, Model, PoseWeights};
    ///
    /// let model = Model::parse(include_bytes!("../../fixtures/golden/v1-world.aprt"))?;
    /// let (mut pose, mut lit) = (PoseWeights::new(), LitWeights::new());
    /// model.set_pose(&[0.0; 4], &mut pose)?;
    /// model.light(&pose, &[1.0; 9], &[], &mut lit)?;
    /// let (mut all, mut part) = (vec![0.0; model.info().vertices()], [0.0; 5]);
    /// model.shade(&lit, 0, &mut all)?;
    /// model.shade(&lit, 3, &mut part)?;
    /// assert_eq!(part, all[3..8]);
    /// # Ok::<(), aprt_core::Error>(())
    /// ```
    pub fn shade<const L: usize>(
        &self,
        lit: &LitWeights<L>,
        first: usize,
        out: &mut [f32],
    ) -> Result<(), Error> {
        self.info.shade(&mut Resident(self.blob), lit, first, out)
    }

    /// Per-vertex transfer of vertices `first ..`, n² values each, vertex-major, into `out`
    /// (`count · n²` values), for a GPU that does the lighting dot product. A bone-frame model
    /// gives each vertex's transfer in its bone's frame ([`Model::vertex_bones`]): light it
    /// with that bone's rotated lighting.
    ///
    /// ```
    /// use aprt_core::{Model, PoseWeights};
    ///
    /// let model = Model::parse(include_bytes!("../../fixtures/golden/v1-world.aprt"))?;
    /// let mut pose = PoseWeights::new();
    /// model.set_pose(&[0.0; 4], &mut pose)?;
    /// let mut transfer = vec![0.0; 2 * model.info().coeffs()];
    /// model.transfer(&pose, 10, &mut transfer)?; // vertices 10 and 11
    /// # Ok::<(), aprt_core::Error>(())
    /// ```
    pub fn transfer<const P: usize>(
        &self,
        pose: &PoseWeights<P>,
        first: usize,
        out: &mut [f32],
    ) -> Result<(), Error> {
        self.info
            .transfer(&mut Resident(self.blob), pose, first, out)
    }

    /// The bone of each vertex `first .. first + out.len()` (all 0 for a world-frame model),
    /// for engines that light [`Model::transfer`] output on the GPU.
    ///
    /// ```
    /// let model = aprt_core::Model::parse(include_bytes!("../../fixtures/golden/v1-bones.aprt"))?;
    /// let mut bones = [0u16; 4];
    /// model.vertex_bones(0, &mut bones)?;
    /// assert!(bones.iter().all(|&b| (b as usize) < model.info().bones()));
    /// # Ok::<(), aprt_core::Error>(())
    /// ```
    pub fn vertex_bones(&self, first: usize, out: &mut [u16]) -> Result<(), Error> {
        self.info.vertex_bones(&mut Resident(self.blob), first, out)
    }

    /// Pushes an irradiance rig's K SH vectors (`vectors`, K n² RGB values, vector-major, from
    /// [`IrradianceRig::vectors_from`]) through the pose weights, per colour channel, as
    /// [`Model::light`] does for one lighting vector. `lit` must hold
    /// [`ModelInfo::rig_lit_weights_len`] values.
    pub fn light_rig<const P: usize>(
        &self,
        pose: &PoseWeights<P>,
        vectors: &[[f32; 3]],
        bones: &[Rotation],
        lit: &mut RigLitWeights<'_>,
    ) -> Result<(), Error> {
        self.info.light_rig(pose, vectors, bones, lit)
    }

    /// Per-vertex RGB shading under the rig's lighting at each vertex's own position:
    /// `Σ_k φ_k(p_j) t_j · C_k`, self-shadowed by the vertex's transfer. `positions` are the
    /// world positions of vertices `first .. first + out.len()` this frame (skinned by the
    /// caller), `placement` the root frame's place in the world. Multiply by albedo / π for
    /// exit radiance.
    pub fn shade_rig(
        &self,
        lit: &RigLitWeights<'_>,
        rig: &IrradianceRig<'_>,
        placement: &Placement,
        positions: &[[f32; 3]],
        first: usize,
        out: &mut [[f32; 3]],
    ) -> Result<(), Error> {
        self.info.shade_rig(
            &mut Resident(self.blob),
            lit,
            rig,
            placement,
            positions,
            first,
            out,
        )
    }

    /// Poses the model's occluder proxies for this frame: each sphere moved by its bone's
    /// skinning matrix (`skinning`, one per bone, bind pose to posed, the matrices an engine
    /// computes for linear blend skinning), and per bone the proxies that can reach its
    /// vertices. [`Error::NoProxies`] when the model has none ([`ModelInfo::has_proxies`]).
    ///
    /// A model with proxies learnt its transfer plus the proxies' occlusion: call this, then
    /// [`Model::occlude`] after [`Model::shade`] (or [`Model::occlude_transfer`] after
    /// [`Model::transfer`]), every frame. Without them such a model is too bright wherever
    /// a part of the character shades another.
    pub fn pose_proxies(&self, skinning: &[Skinning], frame: &mut ProxyFrame) -> Result<(), Error> {
        self.info
            .pose_proxies(&mut Resident(self.blob), skinning, frame)
    }

    /// Subtracts from `out` (the [`Model::shade`] output of vertices `first .. first +
    /// out.len()`) what the posed proxies block under the world SH `lighting` (n², as given
    /// to [`Model::light`]): `out_j −= Σ_c L_c D_jc`. `positions` and `normals` are the
    /// vertices' posed world positions and normals (the caller's skinned mesh); a zero normal
    /// sees no proxy. Its cost is a few dozen operations per vertex and proxy within reach.
    ///
    /// ```
    /// use aprt_core::{LitWeights, Model, PoseWeights, ProxyFrame};
    ///
    /// let model = Model::parse(include_bytes!("../../fixtures/golden/v1-proxies.aprt"))?;
    /// let info = *model.info();
    /// let (mut pose, mut lit, mut proxies) = (PoseWeights::new(), LitWeights::new(), ProxyFrame::new());
    /// let identity = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    /// let still = [1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0];
    /// let sky = [1.0, 0.0, 0.8, 0.0];
    /// model.set_pose(&vec![0.0; info.pose_len()], &mut pose)?;
    /// model.light(&pose, &sky, &vec![identity; info.bones()], &mut lit)?;
    /// model.pose_proxies(&vec![still; info.bones()], &mut proxies)?;
    /// let (positions, normals) = (vec![[0.0, 0.0, 0.0]; 4], vec![[0.0, 0.0, 1.0]; 4]);
    /// let mut shading = vec![0.0; 4];
    /// model.shade(&lit, 0, &mut shading)?;
    /// model.occlude(&proxies, &sky, &positions, &normals, 0, &mut shading)?;
    /// # Ok::<(), aprt_core::Error>(())
    /// ```
    pub fn occlude(
        &self,
        frame: &ProxyFrame,
        lighting: &[f32],
        positions: &[[f32; 3]],
        normals: &[[f32; 3]],
        first: usize,
        out: &mut [f32],
    ) -> Result<(), Error> {
        self.info.occlude(
            &mut Resident(self.blob),
            frame,
            lighting,
            positions,
            normals,
            first,
            out,
        )
    }

    /// Calls `visit(i, D)` for each vertex `first + i` (of `positions` and `normals`, posed
    /// world positions and normals) that the posed proxies reach, with its world-frame
    /// occlusion `D` (n² values), for lighting that varies over the character: an irradiance
    /// rig's ([`IrradianceRig::lighting_at`]) or per-vertex lights'. Subtract `Σ_c L_c D_c`
    /// per colour channel from that vertex's [`Model::shade_rig`] or
    /// [`Model::shade_lights`] output, with `L` its lighting there.
    pub fn occlusions(
        &self,
        frame: &ProxyFrame,
        positions: &[[f32; 3]],
        normals: &[[f32; 3]],
        first: usize,
        visit: impl FnMut(usize, &[f32]),
    ) -> Result<(), Error> {
        self.info.occlusions(
            &mut Resident(self.blob),
            frame,
            (positions, normals),
            first,
            visit,
        )
    }

    /// Subtracts the proxies' occlusion `D_j` from [`Model::transfer`] output (`out`, n² per
    /// vertex of `first ..`), in each vertex's bone frame (`bones` as in [`Model::light`]).
    #[allow(clippy::too_many_arguments)]
    pub fn occlude_transfer(
        &self,
        frame: &ProxyFrame,
        bones: &[Rotation],
        positions: &[[f32; 3]],
        normals: &[[f32; 3]],
        first: usize,
        out: &mut [f32],
    ) -> Result<(), Error> {
        self.info.occlude_transfer(
            &mut Resident(self.blob),
            frame,
            bones,
            positions,
            normals,
            first,
            out,
        )
    }

    /// Adds (`+=`) to `out` the RGB shading of vertices `first .. first + out.len()` under
    /// `lights`, each evaluated at the vertex's own world position (`positions`, one per
    /// vertex, skinned by the caller) and scaled by `weights[i]`, its per-vertex share
    /// (`1 −` [`IrradianceRig::rig_share`]): `Σ_i w_i t_j · l_i(p_j)`, `t_j` the vertex's
    /// transfer for `pose` (in its bone's frame for a bone-frame model, `bones` as in
    /// [`Model::light`]).
    ///
    /// Lights near the character vary too fast for a rig; evaluated per vertex against its
    /// transfer they stay self-shadowed (*Irradiance Rigs*). Each vertex costs its transfer
    /// once, then per light its bands, one rotated direction and one SH basis evaluation. A
    /// weight of 0 skips the light; a vertex on a point light is inside the small sphere it is
    /// ([`POINT_LIGHT_RADIUS`](crate::POINT_LIGHT_RADIUS)). Everything is checked before anything is written.
    ///
    /// ```
    /// use aprt_core::{Light, Model, PointLight, PoseWeights};
    ///
    /// let model = Model::parse(include_bytes!("../../fixtures/golden/v1-world.aprt"))?;
    /// let mut pose = PoseWeights::new();
    /// model.set_pose(&[0.0; 4], &mut pose)?;
    /// let lamp = Light::Point(PointLight { position: [0.0, 0.0, 2.0], intensity: [1.0; 3] });
    /// let positions = [[0.0, 0.0, 0.0], [0.5, 0.0, 0.0]];
    /// let mut rgb = [[0.0; 3]; 2];
    /// model.shade_lights(&pose, &[], &[lamp], &[1.0], &positions, 4, &mut rgb)?;
    /// # Ok::<(), aprt_core::Error>(())
    /// ```
    #[allow(clippy::too_many_arguments)]
    pub fn shade_lights<const P: usize>(
        &self,
        pose: &PoseWeights<P>,
        bones: &[Rotation],
        lights: &[Light],
        weights: &[f32],
        positions: &[[f32; 3]],
        first: usize,
        out: &mut [[f32; 3]],
    ) -> Result<(), Error> {
        self.info.shade_lights(
            &mut Resident(self.blob),
            pose,
            bones,
            lights,
            weights,
            positions,
            first,
            out,
        )
    }
}

/// A model read from a [`BlobSource`] (flash, a file) through a caller-owned buffer, so the
/// blob is never resident. Its calls are those of [`Model`], on `&mut self`.
///
/// ```
/// use aprt_core::{Error, LitWeights, PoseWeights, StreamedModel};
///
/// let blob: &[u8] = include_bytes!("../../fixtures/golden/v1-world.aprt");
/// // Any BlobSource; a slice copies on every read, as flash would.
/// let mut scratch = [0u8; 16];
/// let Err(Error::BufferTooSmall { needed }) = StreamedModel::open(blob, &mut scratch) else {
///     panic!("16 bytes cannot hold a block of vertex rows");
/// };
/// let mut scratch = vec![0u8; needed];
/// let mut model = StreamedModel::open(blob, &mut scratch)?;
/// let (mut pose, mut lit) = (PoseWeights::new(), LitWeights::new());
/// model.set_pose(&[0.0; 4], &mut pose)?;
/// model.light(&pose, &[1.0; 9], &[], &mut lit)?;
/// let mut shading = vec![0.0; model.info().vertices()];
/// model.shade(&lit, 0, &mut shading)?;
/// # Ok::<(), Error>(())
/// ```
pub struct StreamedModel<'s, S> {
    src: S,
    scratch: &'s mut [u8],
    info: ModelInfo,
}

/// The buffers a streamed model's calls need, as [`StreamedModel::needs`] reads them from a
/// blob's header: each the [`ModelInfo`] method of the same name once the model is open.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct StreamNeeds {
    /// The scratch [`StreamedModel::open`] takes.
    pub scratch_bytes: usize,
    /// The buffer of [`StreamedModel::irradiance_rig`] (0 without a rig).
    pub irradiance_rig_bytes: usize,
    /// The buffer of [`StreamedModel::texel_atlas`] (0 without an atlas).
    pub texel_atlas_bytes: usize,
    /// The buffer of [`StreamedModel::angle_names`] (0 without names).
    pub angle_names_bytes: usize,
}

/// The dimensions and the blob's length, not its bytes.
impl core::fmt::Debug for Model<'_> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("Model")
            .field("bytes", &self.blob.len())
            .field("info", &self.info)
            .finish()
    }
}

/// The dimensions and the buffer's size, not the source or its bytes.
impl<S> core::fmt::Debug for StreamedModel<'_, S> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("StreamedModel")
            .field("scratch_bytes", &self.scratch.len())
            .field("info", &self.info)
            .finish_non_exhaustive()
    }
}

impl<'s, S: BlobSource> StreamedModel<'s, S> {
    /// Validates the blob in `src` completely, as [`Model::parse`] does, streaming it through
    /// `scratch`, which the model keeps for its calls. `scratch` must hold
    /// [`ModelInfo::scratch_bytes`] (one block of eight vertex rows; `aprt inspect` prints
    /// it). The size is read from the header first: a smaller buffer gives
    /// [`Error::BufferTooSmall`] with that size before the sections are read, so asking
    /// costs what [`StreamedModel::needs`] does, and only a call that can open the model
    /// streams the whole blob.
    pub fn open(mut src: S, scratch: &'s mut [u8]) -> Result<StreamedModel<'s, S>, Error> {
        let len = scratch.len();
        // Validation reads items of at most 4 bytes: a buffer too small even for that is
        // replaced by one on the stack, so the error names what evaluation needs.
        let mut fallback = [0u8; 64];
        let mut reader = Streaming {
            src: &mut src,
            scratch: match len < fallback.len() {
                true => &mut fallback[..],
                false => &mut *scratch,
            },
        };
        let layout = ModelInfo::layout(&mut reader)?;
        let needed = layout.info.scratch_bytes();
        if len < needed {
            return Err(Error::BufferTooSmall { needed });
        }
        let info = layout.verify(&mut reader)?;
        Ok(StreamedModel { src, scratch, info })
    }

    /// What opening the blob in `src` takes, read from its header and section table (a few
    /// hundred bytes, and the pose features' flags when it has them) without streaming the
    /// sections. The blob is not validated: [`open`](Self::open) may still refuse it, but
    /// never for a buffer of these sizes.
    ///
    /// ```
    /// use aprt_core::StreamedModel;
    ///
    /// let blob: &[u8] = include_bytes!("../../fixtures/golden/v1-bones.aprt");
    /// let needs = StreamedModel::needs(blob)?;
    /// let mut scratch = vec![0u8; needs.scratch_bytes];
    /// let model = StreamedModel::open(blob, &mut scratch)?;
    /// assert_eq!(model.info().scratch_bytes(), needs.scratch_bytes);
    /// # Ok::<(), aprt_core::Error>(())
    /// ```
    pub fn needs(mut src: S) -> Result<StreamNeeds, Error> {
        let mut buf = [0u8; 64];
        let info = ModelInfo::layout(&mut Streaming {
            src: &mut src,
            scratch: &mut buf,
        })?
        .info;
        Ok(StreamNeeds {
            scratch_bytes: info.scratch_bytes(),
            irradiance_rig_bytes: info.irradiance_rig_bytes(),
            texel_atlas_bytes: info.texel_atlas_bytes(),
            angle_names_bytes: info.angle_names_bytes(),
        })
    }

    fn reader(&mut self) -> Streaming<'_, S> {
        Streaming {
            src: &mut self.src,
            scratch: &mut *self.scratch,
        }
    }

    /// The model's dimensions and what its calls need.
    pub fn info(&self) -> &ModelInfo {
        &self.info
    }

    /// The names of the pose-vector entries, read into `buf`, which must hold
    /// [`ModelInfo::angle_names_bytes`]. Empty when the blob records none.
    ///
    /// ```
    /// use aprt_core::StreamedModel;
    ///
    /// let blob: &[u8] = include_bytes!("../../fixtures/golden/v1-bones.aprt");
    /// let mut scratch = [0u8; 512];
    /// let mut model = StreamedModel::open(blob, &mut scratch)?;
    /// let mut buf = [0u8; 64];
    /// assert_eq!(model.angle_names(&mut buf)?.index_of("l_elbow"), Some(3));
    /// # Ok::<(), aprt_core::Error>(())
    /// ```
    pub fn angle_names<'b>(&mut self, buf: &'b mut [u8]) -> Result<AngleNames<'b>, Error> {
        let Some(span) = self.info.angle_names else {
            return Ok(AngleNames::default());
        };
        let needed = self.info.angle_names_bytes();
        let dst = buf
            .get_mut(..needed)
            .ok_or(Error::BufferTooSmall { needed })?;
        self.src
            .read_at(span.offset, dst)
            .map_err(|_| Error::Source)?;
        // Checked again: the source may have changed since `open`.
        AngleNames::parse(dst, self.info.pose_len)
    }

    /// [`Model::set_pose`], streaming the pose sections.
    pub fn set_pose<const N: usize>(
        &mut self,
        angles: &[f32],
        pose: &mut PoseWeights<N>,
    ) -> Result<(), Error> {
        let info = self.info;
        info.set_pose(&mut self.reader(), angles, pose)
    }

    /// [`Model::light`]: reads no blob bytes.
    pub fn light<const P: usize, const L: usize>(
        &self,
        pose: &PoseWeights<P>,
        lighting: &[f32],
        bones: &[Rotation],
        lit: &mut LitWeights<L>,
    ) -> Result<(), Error> {
        self.info.light(pose, lighting, bones, lit)
    }

    /// [`Model::shade`], streaming the blocks of the range.
    pub fn shade<const L: usize>(
        &mut self,
        lit: &LitWeights<L>,
        first: usize,
        out: &mut [f32],
    ) -> Result<(), Error> {
        let info = self.info;
        info.shade(&mut self.reader(), lit, first, out)
    }

    /// [`Model::transfer`], streaming the blocks of the range.
    pub fn transfer<const P: usize>(
        &mut self,
        pose: &PoseWeights<P>,
        first: usize,
        out: &mut [f32],
    ) -> Result<(), Error> {
        let info = self.info;
        info.transfer(&mut self.reader(), pose, first, out)
    }

    /// [`Model::vertex_bones`], streaming the blocks of the range.
    pub fn vertex_bones(&mut self, first: usize, out: &mut [u16]) -> Result<(), Error> {
        let info = self.info;
        info.vertex_bones(&mut self.reader(), first, out)
    }

    /// The irradiance rig, read into `buf` (at least [`ModelInfo::irradiance_rig_bytes`]) and
    /// validated; [`Error::NoIrradianceRig`] when the model has none.
    pub fn irradiance_rig<'b>(&mut self, buf: &'b mut [u8]) -> Result<IrradianceRig<'b>, Error> {
        let span = self.info.irradiance_rig.ok_or(Error::NoIrradianceRig)?;
        let len = span.len as usize;
        let dst = buf
            .get_mut(..len)
            .ok_or(Error::BufferTooSmall { needed: len })?;
        self.reader().chunks(span.offset, 1, len, |at, bytes| {
            dst[at..at + bytes.len()].copy_from_slice(bytes);
            Ok(())
        })?;
        IrradianceRig::parse(dst)
    }

    /// The texel atlas, read into `buf` (at least [`ModelInfo::texel_atlas_bytes`]) and
    /// validated again (the source may have changed since `open`); `None` when the model
    /// records none.
    pub fn texel_atlas<'b>(&mut self, buf: &'b mut [u8]) -> Result<Option<TexelAtlas<'b>>, Error> {
        let Some(span) = self.info.texel_atlas else {
            return Ok(None);
        };
        let len = span.len as usize;
        let dst = buf
            .get_mut(..len)
            .ok_or(Error::BufferTooSmall { needed: len })?;
        self.reader().chunks(span.offset, 1, len, |at, bytes| {
            dst[at..at + bytes.len()].copy_from_slice(bytes);
            Ok(())
        })?;
        TexelAtlas::parse(dst, self.info.vertices).map(Some)
    }

    /// As [`Model::light_rig`].
    pub fn light_rig<const P: usize>(
        &mut self,
        pose: &PoseWeights<P>,
        vectors: &[[f32; 3]],
        bones: &[Rotation],
        lit: &mut RigLitWeights<'_>,
    ) -> Result<(), Error> {
        self.info.light_rig(pose, vectors, bones, lit)
    }

    /// As [`Model::shade_rig`].
    pub fn shade_rig(
        &mut self,
        lit: &RigLitWeights<'_>,
        rig: &IrradianceRig<'_>,
        placement: &Placement,
        positions: &[[f32; 3]],
        first: usize,
        out: &mut [[f32; 3]],
    ) -> Result<(), Error> {
        let info = self.info;
        info.shade_rig(
            &mut self.reader(),
            lit,
            rig,
            placement,
            positions,
            first,
            out,
        )
    }

    /// As [`Model::pose_proxies`], reading the proxies through the buffer.
    pub fn pose_proxies(
        &mut self,
        skinning: &[Skinning],
        frame: &mut ProxyFrame,
    ) -> Result<(), Error> {
        let info = self.info;
        info.pose_proxies(&mut self.reader(), skinning, frame)
    }

    /// As [`Model::occlude`], streaming the bone rows of the range.
    pub fn occlude(
        &mut self,
        frame: &ProxyFrame,
        lighting: &[f32],
        positions: &[[f32; 3]],
        normals: &[[f32; 3]],
        first: usize,
        out: &mut [f32],
    ) -> Result<(), Error> {
        let info = self.info;
        info.occlude(
            &mut self.reader(),
            frame,
            lighting,
            positions,
            normals,
            first,
            out,
        )
    }

    /// As [`Model::occlusions`], streaming the bone rows of the range.
    pub fn occlusions(
        &mut self,
        frame: &ProxyFrame,
        positions: &[[f32; 3]],
        normals: &[[f32; 3]],
        first: usize,
        visit: impl FnMut(usize, &[f32]),
    ) -> Result<(), Error> {
        let info = self.info;
        info.occlusions(
            &mut self.reader(),
            frame,
            (positions, normals),
            first,
            visit,
        )
    }

    /// As [`Model::occlude_transfer`], streaming the bone rows of the range.
    #[allow(clippy::too_many_arguments)]
    pub fn occlude_transfer(
        &mut self,
        frame: &ProxyFrame,
        bones: &[Rotation],
        positions: &[[f32; 3]],
        normals: &[[f32; 3]],
        first: usize,
        out: &mut [f32],
    ) -> Result<(), Error> {
        let info = self.info;
        info.occlude_transfer(
            &mut self.reader(),
            frame,
            bones,
            positions,
            normals,
            first,
            out,
        )
    }

    /// As [`Model::shade_lights`], streaming the blocks of the range.
    #[allow(clippy::too_many_arguments)]
    pub fn shade_lights<const P: usize>(
        &mut self,
        pose: &PoseWeights<P>,
        bones: &[Rotation],
        lights: &[Light],
        weights: &[f32],
        positions: &[[f32; 3]],
        first: usize,
        out: &mut [[f32; 3]],
    ) -> Result<(), Error> {
        let info = self.info;
        info.shade_lights(
            &mut self.reader(),
            pose,
            bones,
            lights,
            weights,
            positions,
            first,
            out,
        )
    }
}
