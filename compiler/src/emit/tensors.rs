//! `graphs.safetensors`, written a chunk of samples at a time.
//!
//! The file's header (every tensor's dtype, shape and byte range) is known
//! from the dataset's [`Shape`] before any sample is built, so it is
//! written first, and each chunk's rows are then written into every
//! tensor's range at their offset: memory holds one chunk, not the
//! dataset. The layout is the `safetensors` crate's own (tensors by
//! descending dtype alignment, then name; header padded with spaces to 8
//! bytes), so the bytes equal `safetensors::serialize` of the same
//! tensors (a unit test checks it).
//!
//! Invariant: [`TensorsWriter::finish`] fails unless exactly
//! `shape.samples` samples were written, in order, each with
//! `shape.width` node columns.

use crate::artifact::{schema, tensor};
use crate::dataset::{Graphs, Shape, edge_index};
use crate::error::Error;
use crate::output::OutputFile;
use safetensors::tensor::{Dtype, Metadata, TensorInfo};
use std::collections::HashMap;
use std::io::{Seek, SeekFrom, Write};

/// Bytes of one sample's row in each per-sample tensor, and the tensor's
/// extra dimensions.
fn rows(width: usize) -> [(&'static str, Dtype, Vec<usize>); 7] {
    [
        (tensor::NODES, Dtype::F32, vec![width, 4]),
        (tensor::NODE_MASK, Dtype::U8, vec![width]),
        (tensor::GOAL, Dtype::F32, vec![3]),
        (tensor::TARGET, Dtype::I64, vec![]),
        (tensor::LABEL, Dtype::I64, vec![]),
        (tensor::STAGE, Dtype::U8, vec![]),
        (tensor::DEMO, Dtype::I64, vec![]),
    ]
}

fn le_bytes<T: Copy, const N: usize>(values: &[T], to: impl Fn(T) -> [u8; N]) -> Vec<u8> {
    values.iter().flat_map(|&v| to(v)).collect()
}

/// The bytes of tensor `name` in `g` (its rows, or the edges).
fn bytes_of(g: &Graphs, name: &str) -> Vec<u8> {
    match name {
        tensor::NODES => le_bytes(&g.nodes, f32::to_le_bytes),
        tensor::NODE_MASK => g.node_mask.clone(),
        tensor::GOAL => le_bytes(&g.goal, f32::to_le_bytes),
        tensor::TARGET => le_bytes(&g.target, i64::to_le_bytes),
        tensor::LABEL => le_bytes(&g.label, i64::to_le_bytes),
        tensor::STAGE => g.stage.clone(),
        tensor::DEMO => le_bytes(&g.demo, i64::to_le_bytes),
        _ => le_bytes(&g.edge_index, i64::to_le_bytes),
    }
}

fn internal(what: impl ToString) -> Error {
    Error::Internal {
        what: what.to_string(),
    }
}

/// Where one tensor's data lies, from the start of the data.
struct Range {
    name: &'static str,
    start: u64,
    /// Bytes per sample (0 for `edge_index`).
    row: u64,
}

/// `graphs.safetensors` being written.
pub(super) struct TensorsWriter {
    file: Box<dyn OutputFile>,
    data_start: u64,
    ranges: Vec<Range>,
    shape: Shape,
    written: usize,
}

impl TensorsWriter {
    /// Writes the header of a file of `shape`, and the edges.
    pub(super) fn start(
        mut file: Box<dyn OutputFile>,
        shape: Shape,
    ) -> Result<TensorsWriter, Error> {
        let s = shape.samples;
        let mut tensors: Vec<(&'static str, Dtype, Vec<usize>)> = rows(shape.width)
            .into_iter()
            .map(|(name, dtype, dims)| {
                let mut full = vec![s];
                full.extend(dims);
                (name, dtype, full)
            })
            .collect();
        tensors.push((tensor::EDGE_INDEX, Dtype::I64, vec![2, shape.edges()]));
        tensors.sort_by(|(a, da, _), (b, db, _)| db.cmp(da).then(a.cmp(b)));
        let mut offset = 0usize;
        let mut infos = Vec::new();
        let mut ranges = Vec::new();
        for (name, dtype, full) in &tensors {
            let n = full.iter().product::<usize>() * dtype.bitsize() / 8;
            let per_sample = if *name == tensor::EDGE_INDEX {
                0
            } else {
                full[1..].iter().product::<usize>() * dtype.bitsize() / 8
            };
            infos.push((
                name.to_string(),
                TensorInfo {
                    dtype: *dtype,
                    shape: full.clone(),
                    data_offsets: (offset, offset + n),
                },
            ));
            ranges.push(Range {
                name,
                start: offset as u64,
                row: per_sample as u64,
            });
            offset += n;
        }
        let metadata = HashMap::from([("schema".to_owned(), schema::GRAPHS.to_owned())]);
        let metadata = Metadata::new(Some(metadata), infos).map_err(internal)?;
        let mut header = serde_json::to_string(&metadata)
            .map_err(internal)?
            .into_bytes();
        header.resize(header.len().next_multiple_of(8), b' ');
        let write = |e: std::io::Error| Error::Write {
            file: super::file::GRAPHS.into(),
            reason: e.to_string(),
        };
        file.write_all(&(header.len() as u64).to_le_bytes())
            .and_then(|()| file.write_all(&header))
            .map_err(write)?;
        let data_start = 8 + header.len() as u64;
        let mut writer = TensorsWriter {
            file,
            data_start,
            ranges,
            shape,
            written: 0,
        };
        let edges = Graphs {
            edge_index: edge_index(shape.width),
            ..Graphs::default()
        };
        writer.put(tensor::EDGE_INDEX, 0, &bytes_of(&edges, tensor::EDGE_INDEX))?;
        Ok(writer)
    }

    fn put(&mut self, name: &str, row: usize, bytes: &[u8]) -> Result<(), Error> {
        let Some(range) = self.ranges.iter().find(|r| r.name == name) else {
            return Err(internal(format!("no tensor {name}")));
        };
        let at = self.data_start + range.start + row as u64 * range.row;
        self.file
            .seek(SeekFrom::Start(at))
            .and_then(|_| self.file.write_all(bytes))
            .map_err(|e| Error::Write {
                file: super::file::GRAPHS.into(),
                reason: e.to_string(),
            })
    }

    /// Writes the samples of `g`, the next `g.s` of the dataset.
    pub(super) fn write(&mut self, g: &Graphs) -> Result<(), Error> {
        if g.m != self.shape.width
            || g.nodes.len() != g.s * g.m * 4
            || self.written + g.s > self.shape.samples
        {
            return Err(internal(format!(
                "a chunk of {} samples with {} columns does not fit the dataset's {} x {} at sample {}",
                g.s, g.m, self.shape.samples, self.shape.width, self.written
            )));
        }
        for (name, _, _) in rows(self.shape.width) {
            self.put(name, self.written, &bytes_of(g, name))?;
        }
        self.written += g.s;
        Ok(())
    }

    /// Ends the file; its length.
    pub(super) fn finish(self) -> Result<u64, Error> {
        if self.written != self.shape.samples {
            return Err(internal(format!(
                "{} samples written of {}",
                self.written, self.shape.samples
            )));
        }
        self.file.finish().map_err(|e| Error::Write {
            file: super::file::GRAPHS.into(),
            reason: e.to_string(),
        })
    }
}

/// `graphs.safetensors` of graphs held in memory (all of a dataset), with
/// the `safetensors` crate: for tests and tools.
pub fn serialize(g: &Graphs) -> Result<Vec<u8>, Error> {
    use safetensors::tensor::TensorView;
    let (s, m, e) = (g.s, g.m, g.edges());
    let data: Vec<(&str, Dtype, Vec<usize>, Vec<u8>)> = rows(m)
        .into_iter()
        .map(|(name, dtype, dims)| {
            let mut full = vec![s];
            full.extend(dims);
            (name, dtype, full, bytes_of(g, name))
        })
        .chain(std::iter::once((
            tensor::EDGE_INDEX,
            Dtype::I64,
            vec![2, e],
            bytes_of(g, tensor::EDGE_INDEX),
        )))
        .collect();
    let views = data
        .iter()
        .map(|(name, dtype, shape, bytes)| {
            TensorView::new(*dtype, shape.clone(), bytes).map(|v| (*name, v))
        })
        .collect::<Result<Vec<_>, _>>()
        .map_err(internal)?;
    let metadata = HashMap::from([("schema".to_owned(), schema::GRAPHS.to_owned())]);
    safetensors::serialize(views, Some(metadata)).map_err(internal)
}
