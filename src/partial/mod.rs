//! Partial renders on disk (`.strata`): the film of one sample slice or of
//! an unfinished checkpoint, checked before parts are combined.
//!
//! [`format`](mod@format) reads and writes the files, [`fingerprint`] identifies the
//! scene a part belongs to, and [`merge`] sums parts into the film one
//! process would have made.

pub mod fingerprint;
pub mod format;
pub mod merge;

pub use format::{read_partial, write_partial, Partial, PartialHeader};
