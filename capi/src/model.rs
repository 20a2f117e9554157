//! The model handle: a resident blob read in place, or a blob streamed through a C read
//! callback and the caller's scratch. Both live in storage the caller lends
//! (`aprt_model_size()` bytes aligned to `aprt_model_align()`), hold no resources, and need no
//! destroy call: the caller frees the storage when it is done.
//!
//! Every per-frame call goes through `with_model`, which gives the two kinds one face
//! (`Eval`), so the frame, light, rig and proxies modules never ask which kind they have.
// `#[unsafe(no_mangle)]` is the only unsafe here (exported names must be unique); every
// unsafe operation lives in `ffi_ptr`, which `tests/unsafe_confined.rs` checks.
#![allow(unsafe_code)]

use std::cell::RefCell;
use std::ffi::c_void;

use aprt_core::{
    BlobSource, Error, Frame, IrradianceRig, Light, LitWeights, Model, ModelInfo, Placement,
    PoseWeights, ProxyFrame, RigLitWeights, Rotation, Skinning, SourceError, StreamedModel,
};

use crate::ffi_ptr::{self, Handle, ReadFn};
use crate::status::{aprt_status, guard};

/// Reads `len` bytes of the blob at byte `offset` into `buf`; returns 0 on success and any
/// other value on failure (the call then returns `APRT_STATUS_SOURCE`). The library only asks
/// for ranges inside `0 .. len` of the source. It must not unwind (no C++ exception may leave
/// it), must not keep `buf`, and must not call the model it is reading for.
#[allow(non_camel_case_types)]
pub type aprt_read_fn =
    Option<unsafe extern "C" fn(user: *mut c_void, offset: u64, buf: *mut u8, len: usize) -> i32>;

/// A blob that is not in memory (flash, a file): its length and a read callback. Copied by
/// `aprt_model_stream_init`; `user` is passed back to every read and must stay valid while
/// the model is used.
#[allow(non_camel_case_types)]
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct aprt_source {
    /// The read callback (not NULL).
    pub read_at: aprt_read_fn,
    /// Passed to `read_at` unchanged.
    pub user: *mut c_void,
    /// The blob's length in bytes.
    pub len: u64,
}

/// `transfer` is in world space: one SH lighting vector shades every vertex.
pub const APRT_FRAME_WORLD: u32 = 0;
/// `transfer` is in each vertex's bone frame: `aprt_light_sh` needs every bone's rotation.
pub const APRT_FRAME_BONES: u32 = 1;

/// A model's dimensions and what its calls need (`aprt_model_get_info`).
#[allow(non_camel_case_types)]
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct aprt_model_info {
    /// SH order n (bands 0 .. n).
    pub order: u32,
    /// n²: the coefficients of the SH lighting and of each vertex's transfer.
    pub coeffs: u32,
    /// Vertices.
    pub vertices: u32,
    /// Entries of the pose vector `aprt_set_pose` takes.
    pub pose_len: u32,
    /// Bone rotations `aprt_light_sh`, `aprt_shade_lights` and `aprt_light_rig` take (0 for a
    /// world-frame model, which accepts none).
    pub bones: u32,
    /// `APRT_FRAME_WORLD` or `APRT_FRAME_BONES`.
    pub frame: u32,
    /// The irradiance rig's SH vectors K (0 without a rig): `aprt_rig_vectors` writes
    /// K · coeffs RGB triples.
    pub rig_vectors: u32,
    /// The model's identity (the CRC-32 of its header): a frame computed for one model is
    /// refused by another.
    pub id: u32,
    /// Whether the model carries an irradiance rig.
    pub has_rig: bool,
    /// Whether the model is a light-map model with a texel atlas.
    pub has_atlas: bool,
    /// Whether the handle streams its blob through a read callback.
    pub streamed: bool,
    /// Whether the model carries occluder proxies: then every frame needs
    /// `aprt_pose_proxies` and `aprt_occlude` (or `aprt_occlude_transfer`). (It sits in what
    /// was padding, so the struct's size and other offsets are those of ABI version 1.)
    pub has_proxies: bool,
    /// Scratch bytes `aprt_model_stream_init` needs for this model (one block of vertex rows,
    /// plus the irradiance rig when there is one): keep it with the blob, and the next stream
    /// init of it needs no size query.
    pub scratch_bytes: usize,
    /// Floats the buffer of `aprt_light_rig` needs (0 without a rig).
    pub rig_lit_len: usize,
}

/// A validated model in the caller's storage. Opaque; see `aprt_model_init`.
// `repr(C)`: the tag first, as in every handle; `align(8)` makes cbindgen declare it opaque.
#[allow(non_camel_case_types)]
#[repr(C, align(8))]
pub struct aprt_model {
    tag: u64,
    kind: Kind,
}

enum Kind {
    /// `Model` is `Copy`: each call evaluates a copy, so a resident handle is only read and
    /// may be shared by threads shading disjoint ranges.
    Resident(Model<'static>),
    /// A streamed model reads through its scratch, so it is borrowed mutably per call; the
    /// `RefCell` turns re-entry from the read callback into `APRT_STATUS_BUSY`.
    Streamed(RefCell<Streamed>),
}

impl Handle for aprt_model {
    const TAG: u64 = u64::from_le_bytes(*b"aprtMODL");
    const TAG_OFFSET: usize = std::mem::offset_of!(aprt_model, tag);
}

/// The C callback as a [`BlobSource`].
struct CSource {
    read: ReadFn,
    user: *mut c_void,
    len: u64,
}

impl BlobSource for CSource {
    fn len(&self) -> u64 {
        self.len
    }

    fn read_at(&mut self, offset: u64, buf: &mut [u8]) -> Result<(), SourceError> {
        match ffi_ptr::call_read(self.read, self.user, offset, buf) {
            0 => Ok(()),
            _ => Err(SourceError),
        }
    }
}

/// A streamed model and its irradiance rig, read once into the tail of the scratch.
pub(crate) struct Streamed {
    model: StreamedModel<'static, CSource>,
    rig: Option<IrradianceRig<'static>>,
}

/// The per-frame calls both kinds of model answer, over the frame's fixed-capacity weights.
pub(crate) trait Eval {
    fn info(&self) -> ModelInfo;
    fn rig(&self) -> Option<IrradianceRig<'static>>;
    fn angle_index(&mut self, name: &str) -> Result<Option<usize>, Error>;
    fn set_pose(&mut self, angles: &[f32], pose: &mut PoseWeights) -> Result<(), Error>;
    fn light(
        &mut self,
        pose: &PoseWeights,
        lighting: &[f32],
        bones: &[Rotation],
        lit: &mut LitWeights,
    ) -> Result<(), Error>;
    fn shade(&mut self, lit: &LitWeights, first: usize, out: &mut [f32]) -> Result<(), Error>;
    fn transfer(&mut self, pose: &PoseWeights, first: usize, out: &mut [f32]) -> Result<(), Error>;
    fn vertex_bones(&mut self, first: usize, out: &mut [u16]) -> Result<(), Error>;
    fn shade_lights(
        &mut self,
        pose: &PoseWeights,
        lights: &LightSet,
        out: Range<'_>,
    ) -> Result<(), Error>;
    fn light_rig(
        &mut self,
        pose: &PoseWeights,
        vectors: &[[f32; 3]],
        bones: &[Rotation],
        lit: &mut RigLitWeights<'_>,
    ) -> Result<(), Error>;
    fn shade_rig(
        &mut self,
        lit: &RigLitWeights<'_>,
        placement: &Placement,
        out: Range<'_>,
    ) -> Result<(), Error>;
    fn pose_proxies(&mut self, skinning: &[Skinning], frame: &mut ProxyFrame) -> Result<(), Error>;
    fn occlude(
        &mut self,
        frame: &ProxyFrame,
        lighting: &[f32],
        positions: &[[f32; 3]],
        normals: &[[f32; 3]],
        first: usize,
        out: &mut [f32],
    ) -> Result<(), Error>;
    #[allow(clippy::too_many_arguments)]
    fn occlude_transfer(
        &mut self,
        frame: &ProxyFrame,
        bones: &[Rotation],
        positions: &[[f32; 3]],
        normals: &[[f32; 3]],
        first: usize,
        out: &mut [f32],
    ) -> Result<(), Error>;
}

/// The lights of one `aprt_shade_lights` call, converted and checked for their kind.
pub(crate) struct LightSet<'a> {
    pub bones: &'a [Rotation],
    pub lights: &'a [Light],
    pub weights: &'a [f32],
}

/// The vertices an RGB call shades: their world positions, the first index, the output.
pub(crate) struct Range<'a> {
    pub positions: &'a [[f32; 3]],
    pub first: usize,
    pub out: &'a mut [[f32; 3]],
}

impl Range<'_> {
    /// `count` positions and RGB outputs from C, the first being vertex `first`.
    pub fn from_c(
        positions: *const f32,
        first: usize,
        out_rgb: *mut f32,
        count: usize,
    ) -> Result<Self, aprt_status> {
        let vertices = ffi_ptr::past_vertices;
        Ok(Range {
            positions: ffi_ptr::triples(positions, count).map_err(vertices)?,
            first,
            out: ffi_ptr::triples_mut(out_rgb, count).map_err(vertices)?,
        })
    }
}

impl Eval for Model<'static> {
    fn info(&self) -> ModelInfo {
        *Model::info(self)
    }
    fn rig(&self) -> Option<IrradianceRig<'static>> {
        self.irradiance_rig()
    }
    fn angle_index(&mut self, name: &str) -> Result<Option<usize>, Error> {
        Ok(self.angle_names().index_of(name))
    }
    fn set_pose(&mut self, angles: &[f32], pose: &mut PoseWeights) -> Result<(), Error> {
        Model::set_pose(self, angles, pose)
    }
    fn light(
        &mut self,
        pose: &PoseWeights,
        lighting: &[f32],
        bones: &[Rotation],
        lit: &mut LitWeights,
    ) -> Result<(), Error> {
        Model::light(self, pose, lighting, bones, lit)
    }
    fn shade(&mut self, lit: &LitWeights, first: usize, out: &mut [f32]) -> Result<(), Error> {
        Model::shade(self, lit, first, out)
    }
    fn transfer(&mut self, pose: &PoseWeights, first: usize, out: &mut [f32]) -> Result<(), Error> {
        Model::transfer(self, pose, first, out)
    }
    fn vertex_bones(&mut self, first: usize, out: &mut [u16]) -> Result<(), Error> {
        Model::vertex_bones(self, first, out)
    }
    fn shade_lights(
        &mut self,
        pose: &PoseWeights,
        l: &LightSet,
        r: Range<'_>,
    ) -> Result<(), Error> {
        let (bones, lights, weights) = (l.bones, l.lights, l.weights);
        Model::shade_lights(
            self,
            pose,
            bones,
            lights,
            weights,
            r.positions,
            r.first,
            r.out,
        )
    }
    fn light_rig(
        &mut self,
        pose: &PoseWeights,
        vectors: &[[f32; 3]],
        bones: &[Rotation],
        lit: &mut RigLitWeights<'_>,
    ) -> Result<(), Error> {
        Model::light_rig(self, pose, vectors, bones, lit)
    }
    fn shade_rig(
        &mut self,
        lit: &RigLitWeights<'_>,
        p: &Placement,
        r: Range<'_>,
    ) -> Result<(), Error> {
        let rig = self.irradiance_rig().ok_or(Error::NoIrradianceRig)?;
        Model::shade_rig(self, lit, &rig, p, r.positions, r.first, r.out)
    }
    fn pose_proxies(&mut self, skinning: &[Skinning], frame: &mut ProxyFrame) -> Result<(), Error> {
        Model::pose_proxies(self, skinning, frame)
    }
    fn occlude(
        &mut self,
        frame: &ProxyFrame,
        lighting: &[f32],
        positions: &[[f32; 3]],
        normals: &[[f32; 3]],
        first: usize,
        out: &mut [f32],
    ) -> Result<(), Error> {
        Model::occlude(self, frame, lighting, positions, normals, first, out)
    }
    fn occlude_transfer(
        &mut self,
        frame: &ProxyFrame,
        bones: &[Rotation],
        positions: &[[f32; 3]],
        normals: &[[f32; 3]],
        first: usize,
        out: &mut [f32],
    ) -> Result<(), Error> {
        Model::occlude_transfer(self, frame, bones, positions, normals, first, out)
    }
}

impl Eval for Streamed {
    fn info(&self) -> ModelInfo {
        *self.model.info()
    }
    fn rig(&self) -> Option<IrradianceRig<'static>> {
        self.rig
    }
    fn angle_index(&mut self, name: &str) -> Result<Option<usize>, Error> {
        // Names are short; a model whose names exceed this refuses with BufferTooSmall.
        let mut buf = [0u8; 8192];
        Ok(self.model.angle_names(&mut buf)?.index_of(name))
    }
    fn set_pose(&mut self, angles: &[f32], pose: &mut PoseWeights) -> Result<(), Error> {
        self.model.set_pose(angles, pose)
    }
    fn light(
        &mut self,
        pose: &PoseWeights,
        lighting: &[f32],
        bones: &[Rotation],
        lit: &mut LitWeights,
    ) -> Result<(), Error> {
        self.model.light(pose, lighting, bones, lit)
    }
    fn shade(&mut self, lit: &LitWeights, first: usize, out: &mut [f32]) -> Result<(), Error> {
        self.model.shade(lit, first, out)
    }
    fn transfer(&mut self, pose: &PoseWeights, first: usize, out: &mut [f32]) -> Result<(), Error> {
        self.model.transfer(pose, first, out)
    }
    fn vertex_bones(&mut self, first: usize, out: &mut [u16]) -> Result<(), Error> {
        self.model.vertex_bones(first, out)
    }
    fn shade_lights(
        &mut self,
        pose: &PoseWeights,
        l: &LightSet,
        r: Range<'_>,
    ) -> Result<(), Error> {
        let (bones, lights, weights) = (l.bones, l.lights, l.weights);
        let (positions, first, out) = (r.positions, r.first, r.out);
        self.model
            .shade_lights(pose, bones, lights, weights, positions, first, out)
    }
    fn light_rig(
        &mut self,
        pose: &PoseWeights,
        vectors: &[[f32; 3]],
        bones: &[Rotation],
        lit: &mut RigLitWeights<'_>,
    ) -> Result<(), Error> {
        self.model.light_rig(pose, vectors, bones, lit)
    }
    fn shade_rig(
        &mut self,
        lit: &RigLitWeights<'_>,
        p: &Placement,
        r: Range<'_>,
    ) -> Result<(), Error> {
        let rig = self.rig.ok_or(Error::NoIrradianceRig)?;
        let (positions, first, out) = (r.positions, r.first, r.out);
        self.model.shade_rig(lit, &rig, p, positions, first, out)
    }
    fn pose_proxies(&mut self, skinning: &[Skinning], frame: &mut ProxyFrame) -> Result<(), Error> {
        self.model.pose_proxies(skinning, frame)
    }
    fn occlude(
        &mut self,
        frame: &ProxyFrame,
        lighting: &[f32],
        positions: &[[f32; 3]],
        normals: &[[f32; 3]],
        first: usize,
        out: &mut [f32],
    ) -> Result<(), Error> {
        self.model
            .occlude(frame, lighting, positions, normals, first, out)
    }
    fn occlude_transfer(
        &mut self,
        frame: &ProxyFrame,
        bones: &[Rotation],
        positions: &[[f32; 3]],
        normals: &[[f32; 3]],
        first: usize,
        out: &mut [f32],
    ) -> Result<(), Error> {
        self.model
            .occlude_transfer(frame, bones, positions, normals, first, out)
    }
}

/// Refuses bone rotations the model does not take: one per bone, and none at all for a
/// world-frame model. The Rust API ignores a world-frame model's rotations (an engine may pass
/// its skeleton's); the C header promises `NULL, 0`, so a count there is a caller's mistake
/// (`WRONG_LENGTH`), not garbage silently accepted.
pub(crate) fn check_bone_count(m: &dyn Eval, bones: &[Rotation]) -> Result<(), aprt_status> {
    match bones.len() == m.info().bones() {
        true => Ok(()),
        false => Err(aprt_status::WrongLength),
    }
}

/// Runs `f` on the model behind `model`: a copy of a resident one, or the streamed one
/// borrowed for the call.
pub(crate) fn with_model<R>(
    model: *const aprt_model,
    f: impl FnOnce(&mut dyn Eval) -> Result<R, aprt_status>,
) -> Result<R, aprt_status> {
    match &ffi_ptr::handle(model)?.kind {
        Kind::Resident(m) => f(&mut { *m }),
        Kind::Streamed(cell) => f(&mut *cell.try_borrow_mut().map_err(|_| aprt_status::Busy)?),
    }
}

/// Bytes of storage an `aprt_model` needs.
#[unsafe(no_mangle)]
pub extern "C" fn aprt_model_size() -> usize {
    size_of::<aprt_model>()
}

/// Alignment the storage of an `aprt_model` needs.
#[unsafe(no_mangle)]
pub extern "C" fn aprt_model_align() -> usize {
    align_of::<aprt_model>()
}

/// Validates a resident blob completely, once (header, sections, checksums, every value), and
/// on success writes a model handle into `storage` (`storage_len` ≥ `aprt_model_size()`
/// bytes, aligned to `aprt_model_align()`) and its address to `*out`.
///
/// The blob is read in place, never copied: `blob` must stay valid and unchanged for as long
/// as the handle is used. The handle holds nothing else and needs no destroy call; free the
/// storage and the blob when done. A resident handle may be used by several threads at once
/// (each with its own frame and outputs). Any bytes give a status; none crash.
#[unsafe(no_mangle)]
pub extern "C" fn aprt_model_init(
    blob: *const u8,
    blob_len: usize,
    storage: *mut c_void,
    storage_len: usize,
    out: *mut *mut aprt_model,
) -> aprt_status {
    guard(|| {
        let blob = ffi_ptr::slice(blob, blob_len)?;
        ffi_ptr::check_storage::<aprt_model>(storage, storage_len)?;
        ffi_ptr::write(out, std::ptr::null_mut())?;
        let model = Model::parse(blob)?;
        let handle = aprt_model {
            tag: aprt_model::TAG,
            kind: Kind::Resident(model),
        };
        ffi_ptr::write(out, ffi_ptr::place(storage, storage_len, handle)?)
    })
}

/// Validates a blob read through `source` (copied) completely, as `aprt_model_init` does,
/// streaming it through the caller's `scratch`, and on success writes a model handle into
/// `storage` and its address to `*out`.
///
/// `scratch` (`scratch_len` bytes) belongs to the model from then on: it must stay valid and
/// untouched while the handle is used. It needs `info.scratch_bytes` (one block of vertex
/// rows, plus the irradiance rig when there is one). When it is too small the call returns
/// `APRT_STATUS_BUFFER_TOO_SMALL` and writes the bytes it needs to `*scratch_needed`; call
/// again with that many.
///
/// Asking is cheap: the size is read from the blob's header and section table (a few hundred
/// bytes through `read_at`) before anything is validated, so the blob may still be refused
/// by the call that has scratch enough. That call reads the whole blob once to validate it
/// (and the rig's bytes once more, into the scratch). A streamed handle must not be used by
/// two threads at once, nor from its own read callback (`APRT_STATUS_BUSY`).
#[unsafe(no_mangle)]
pub extern "C" fn aprt_model_stream_init(
    source: *const aprt_source,
    scratch: *mut u8,
    scratch_len: usize,
    scratch_needed: *mut usize,
    storage: *mut c_void,
    storage_len: usize,
    out: *mut *mut aprt_model,
) -> aprt_status {
    guard(|| {
        let source = ffi_ptr::read(source)?;
        let read = source.read_at.ok_or(aprt_status::NullPointer)?;
        ffi_ptr::write(scratch_needed, 0)?;
        ffi_ptr::check_storage::<aprt_model>(storage, storage_len)?;
        ffi_ptr::write(out, std::ptr::null_mut())?;
        let src = || CSource {
            read,
            user: source.user,
            len: source.len,
        };
        let lend = || ffi_ptr::slice_mut(scratch, scratch_len);
        let mut needed = 0;
        let opened = open_streamed(src, lend, &mut needed);
        ffi_ptr::write(scratch_needed, needed)?;
        let streamed = opened?;
        let handle = aprt_model {
            tag: aprt_model::TAG,
            kind: Kind::Streamed(RefCell::new(streamed)),
        };
        ffi_ptr::write(out, ffi_ptr::place(storage, storage_len, handle)?)
    })
}

/// Opens the stream through the head of the scratch (`lend` lends it) and reads a rig, when
/// the model has one, into the tail. A scratch too small for both sets `needed`.
fn open_streamed(
    src: impl Fn() -> CSource,
    lend: impl FnOnce() -> Result<&'static mut [u8], aprt_status>,
    needed: &mut usize,
) -> Result<Streamed, aprt_status> {
    // The sizes come from the header: a query costs a few hundred bytes of reads, and the
    // call that opens streams the blob once (and the rig once more, into its part).
    let needs = StreamedModel::needs(src())?;
    let (head, rig_bytes) = (needs.scratch_bytes, needs.irradiance_rig_bytes);
    let whole = lend()?;
    let total = head.saturating_add(rig_bytes);
    if whole.len() < total {
        *needed = total;
        return Err(aprt_status::BufferTooSmall);
    }
    let (head, tail) = whole.split_at_mut(head);
    let mut model = StreamedModel::open(src(), head)?;
    let rig = match rig_bytes {
        0 => None,
        _ => Some(model.irradiance_rig(tail)?),
    };
    Ok(Streamed { model, rig })
}

/// Writes the model's dimensions and needs to `*out`.
#[unsafe(no_mangle)]
pub extern "C" fn aprt_model_get_info(
    model: *const aprt_model,
    out: *mut aprt_model_info,
) -> aprt_status {
    guard(|| {
        ffi_ptr::write(out, aprt_model_info::default())?;
        let streamed = matches!(ffi_ptr::handle(model)?.kind, Kind::Streamed(_));
        let info = with_model(model, |m| Ok(describe(&m.info(), m.rig(), streamed)))?;
        ffi_ptr::write(out, info)
    })
}

fn describe(info: &ModelInfo, rig: Option<IrradianceRig<'_>>, streamed: bool) -> aprt_model_info {
    let k = rig.map_or(0, |r| r.vectors());
    let small = |x: usize| u32::try_from(x).unwrap_or(u32::MAX);
    aprt_model_info {
        order: small(info.order()),
        coeffs: small(info.coeffs()),
        vertices: small(info.vertices()),
        pose_len: small(info.pose_len()),
        bones: small(info.bones()),
        frame: match info.frame() {
            Frame::World => APRT_FRAME_WORLD,
            _ => APRT_FRAME_BONES,
        },
        rig_vectors: small(k),
        id: info.id(),
        has_rig: rig.is_some(),
        has_atlas: info.texel_atlas_bytes() > 0,
        streamed,
        has_proxies: info.has_proxies(),
        scratch_bytes: info.scratch_bytes() + info.irradiance_rig_bytes(),
        rig_lit_len: match rig {
            Some(_) => info.rig_lit_weights_len(k),
            None => 0,
        },
    }
}

/// Writes to `*index` the pose-vector entry named `name` (`name_len` bytes of UTF-8, no NUL
/// needed), to bind an engine's joints by name once (`SIZE_MAX` on any failure). `APRT_STATUS_NO_SUCH_NAME` when the
/// model has no entry of that name (or records no names).
#[unsafe(no_mangle)]
pub extern "C" fn aprt_model_angle_index(
    model: *const aprt_model,
    name: *const u8,
    name_len: usize,
    index: *mut usize,
) -> aprt_status {
    guard(|| {
        ffi_ptr::write(index, usize::MAX)?;
        let name = ffi_ptr::slice(name, name_len)?;
        let name = std::str::from_utf8(name).map_err(|_| aprt_status::NoSuchName)?;
        let found = with_model(model, |m| Ok(m.angle_index(name)?))?;
        ffi_ptr::write(index, found.ok_or(aprt_status::NoSuchName)?)
    })
}
