//! URDF text from a file or a string to urdf-rs's tree, bounded in size and
//! depth before the parser runs.

use std::path::Path;

use crate::error::ModelError;
use crate::model::MAX_URDF_BYTES;
use crate::xml_depth::{check_depth, MAX_XML_DEPTH};

/// The URDF text of `path` (at most [`MAX_URDF_BYTES`]).
pub(super) fn read_urdf(path: &Path) -> Result<String, ModelError> {
    use std::io::Read;
    let io = |source| ModelError::Io {
        path: path.to_path_buf(),
        source,
    };
    let file = std::fs::File::open(path).map_err(io)?;
    let mut bytes = Vec::new();
    // one byte more than allowed tells a file that is too large (even one
    // whose size the file system does not report, such as a pipe)
    file.take(MAX_URDF_BYTES + 1)
        .read_to_end(&mut bytes)
        .map_err(io)?;
    if bytes.len() as u64 > MAX_URDF_BYTES {
        return Err(ModelError::TooLarge {
            path: path.to_path_buf(),
            max: MAX_URDF_BYTES,
        });
    }
    String::from_utf8(bytes).map_err(|_| {
        io(std::io::Error::new(
            std::io::ErrorKind::InvalidData,
            "not UTF-8 text",
        ))
    })
}

/// `text` parsed; `origin` (a path, `<urdf>`) names it in errors.
pub(super) fn parse(text: &str, origin: &str) -> Result<urdf_rs::Robot, ModelError> {
    // the parser recurses per nesting level: bound the depth before it runs
    check_depth(text, MAX_XML_DEPTH).map_err(|_| ModelError::TooDeep {
        origin: origin.to_string(),
        max: MAX_XML_DEPTH,
    })?;
    // urdf-rs sorts elements with a string pass before parsing; guard against panics deep in it
    let parsed = std::panic::catch_unwind(|| urdf_rs::read_from_string(text)).map_err(|_| {
        ModelError::Parse {
            origin: origin.to_string(),
            message: "parser failed".into(),
        }
    })?;
    parsed.map_err(|e| ModelError::Parse {
        origin: origin.to_string(),
        message: e.to_string(),
    })
}
