//! The model blob: format definition, validation, and streaming access.

mod error;
pub mod format;
mod model;
mod source;

pub use error::{Dim, Error};
pub use format::*;
pub use model::{Model, Section, read_header};
pub(crate) use source::for_each_chunk;
pub use source::{BlobSource, SliceSource, SourceError};
