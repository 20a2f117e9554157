//! The model blob: its layout, where its bytes come from, and validating it once so that
//! evaluation can trust every offset and length.

mod atlas;
mod error;
pub(crate) mod format;
mod header;
mod info;
mod names;
mod source;
mod validate;

pub use atlas::{MAX_ATLAS_RESOLUTION, MAX_ATLAS_TRIANGLES, TexelAtlas};
pub use error::{Dim, Error, Input};
#[cfg(feature = "format")]
pub use header::read_header;
pub use info::ModelInfo;
pub(crate) use info::Span;
pub use names::AngleNames;
pub use source::{BlobSource, SourceError};
pub(crate) use source::{Reader, Resident, Streaming};
