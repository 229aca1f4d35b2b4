//! What a glTF file is checked for before anything of it is read: each
//! accessor's shape and extent, the buffers' URIs (the file's own folder
//! only) and the attributes' index ranges.

use super::LoadError;
use std::path::{Path, PathBuf};

/// Checks that `accessor` holds elements of one of `types` × `dims` and lies
/// within its buffer view and buffer, so that the `gltf` reader (which
/// asserts or slices on these) can read it; a problem is described in words.
pub(super) fn check_accessor(
    accessor: &gltf::Accessor<'_>,
    types: &[gltf::accessor::DataType],
    dims: gltf::accessor::Dimensions,
    buffers: &[gltf::buffer::Data],
) -> Result<(), String> {
    if !types.contains(&accessor.data_type()) || accessor.dimensions() != dims {
        return Err(format!(
            "holds {:?} {:?} elements, expected {:?} of {:?}",
            accessor.dimensions(),
            accessor.data_type(),
            dims,
            types
        ));
    }
    let size = accessor.size();
    let count = accessor.count();
    if count == 0 {
        return Ok(());
    }
    if let Some(view) = accessor.view() {
        let stride = view.stride().unwrap_or(size);
        check_extent(&view, accessor.offset(), stride, size, count, buffers)?;
    }
    if let Some(sparse) = accessor.sparse() {
        let n = sparse.count();
        if n == 0 || n > count {
            return Err(format!("has {n} sparse entries for {count} elements"));
        }
        let indices = sparse.indices();
        let index_size = indices.index_type().size();
        check_extent(
            &indices.view(),
            indices.offset(),
            index_size,
            index_size,
            n,
            buffers,
        )?;
        let values = sparse.values();
        check_extent(&values.view(), values.offset(), size, size, n, buffers)?;
    }
    Ok(())
}

/// Checks that `count` elements of `size` bytes every `stride` bytes from
/// `offset` lie within `view`, and `view` within its buffer.
fn check_extent(
    view: &gltf::buffer::View<'_>,
    offset: usize,
    stride: usize,
    size: usize,
    count: usize,
    buffers: &[gltf::buffer::Data],
) -> Result<(), String> {
    if stride < size {
        return Err(format!(
            "has a byte stride of {stride}, less than its element size {size}"
        ));
    }
    let end = (count - 1)
        .checked_mul(stride)
        .and_then(|b| b.checked_add(size))
        .and_then(|b| b.checked_add(offset));
    if end.is_none_or(|e| e > view.length()) {
        return Err(format!(
            "reaches past the end of buffer view {} ({} bytes)",
            view.index(),
            view.length()
        ));
    }
    let buffer_len = buffers.get(view.buffer().index()).map_or(0, |d| d.0.len());
    if view
        .offset()
        .checked_add(view.length())
        .is_none_or(|e| e > buffer_len)
    {
        return Err(format!(
            "reads buffer view {}, which reaches past the end of buffer {} ({buffer_len} bytes)",
            view.index(),
            view.buffer().index()
        ));
    }
    Ok(())
}

/// Refuses buffer URIs that could read outside the file's own folder or
/// without end (issue 32, item 2): a security rule, not a glTF one. An
/// external buffer must be a relative path with no `..` component, no
/// scheme but `data:`, naming a regular file (not `/dev/zero`, a FIFO or a
/// symlink to one) that, symbolic links resolved, still lies in the folder.
/// The file of each external buffer, in buffer order (`None` for `data:`
/// URIs and the binary chunk).
pub(super) fn check_buffer_uris(
    path: &Path,
    document: &gltf::Document,
) -> Result<Vec<Option<PathBuf>>, LoadError> {
    let refuse = |index: usize, uri: &str, why: &str| LoadError::Gltf {
        path: path.to_owned(),
        message: format!("buffer {index} uri {uri:?} refused: {why}"),
    };
    let folder = path.parent().unwrap_or(Path::new("."));
    let mut files = Vec::new();
    for buffer in document.buffers() {
        let gltf::buffer::Source::Uri(uri) = buffer.source() else {
            files.push(None);
            continue;
        };
        if uri.starts_with("data:") {
            files.push(None);
            continue;
        }
        let index = buffer.index();
        // Checked as the importer reads it: percent-decoded.
        let Ok(decoded) = urlencoding::decode(uri) else {
            return Err(refuse(index, uri, "not valid percent-encoded UTF-8"));
        };
        let decoded = decoded.as_ref();
        if decoded.contains(':') || decoded.starts_with('/') || decoded.starts_with('\\') {
            return Err(refuse(
                index,
                uri,
                "only relative paths inside the file's folder are read",
            ));
        }
        if decoded.contains('\\') {
            return Err(refuse(
                index,
                uri,
                "backslashes are not path separators here",
            ));
        }
        let relative = Path::new(decoded);
        if relative.components().any(|c| {
            !matches!(
                c,
                std::path::Component::Normal(_) | std::path::Component::CurDir
            )
        }) {
            return Err(refuse(index, uri, "it leaves the file's folder"));
        }
        let target = folder.join(relative);
        let cannot_read = |e: std::io::Error| LoadError::Gltf {
            path: path.to_owned(),
            message: format!(
                "buffer {index} file {} cannot be read: {e}",
                target.display()
            ),
        };
        match std::fs::metadata(&target) {
            Ok(meta) if meta.is_file() => {}
            Ok(_) => return Err(refuse(index, uri, "not a regular file")),
            Err(e) => return Err(cannot_read(e)),
        }
        // A symbolic link (the file or a folder on the way) may lead out.
        let real = std::fs::canonicalize(&target).map_err(cannot_read)?;
        let real_folder = std::fs::canonicalize(folder).map_err(cannot_read)?;
        if !real.starts_with(&real_folder) {
            return Err(refuse(
                index,
                uri,
                "a symbolic link leads out of the file's folder",
            ));
        }
        files.push(Some(real));
    }
    Ok(files)
}

/// Refuses a mesh attribute that names an accessor the file does not have.
pub(super) fn check_attribute_indices(
    path: &Path,
    root: &gltf::json::Root,
) -> Result<(), LoadError> {
    let accessors = root.accessors.len();
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, primitive) in mesh.primitives.iter().enumerate() {
            for (semantic, index) in &primitive.attributes {
                if index.value() >= accessors {
                    let name = match semantic {
                        gltf::json::validation::Checked::Valid(s) => s.to_string(),
                        gltf::json::validation::Checked::Invalid => "an unknown".to_owned(),
                    };
                    return Err(LoadError::Gltf {
                        path: path.to_owned(),
                        message: format!(
                            "not a valid glTF file: mesh {m} primitive {p}: the {name} attribute \
                             names accessor {}, but the file has {accessors}",
                            index.value()
                        ),
                    });
                }
            }
        }
    }
    Ok(())
}
