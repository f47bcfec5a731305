//! Prophesee `.raw` files: an ASCII header of `% key value` lines followed by the event stream.

mod header;
mod reader;
mod writer;

pub use header::{HeaderError, RawHeader, geometry_from_plugin};
pub use reader::{RawFileError, RawReader};
pub use writer::{RawWriteError, RawWriter};
