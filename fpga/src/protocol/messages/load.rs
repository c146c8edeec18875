//! The uploads: LoadModel / LoadScan (points), LoadTable (cell-table entries), and the
//! requests that upload a gridded model with its normals.

use super::put;
use crate::common::format::{FxPoint, MAX_POINTS};
use crate::protocol::layout::{point_bytes, POINT_BYTES};

/// Most points in one LoadModel / LoadScan frame.
pub const MAX_LOAD_POINTS: usize = 170;
/// Bytes of a cell-table entry on the wire (13 bits used).
pub const TABLE_ENTRY_BYTES: usize = 2;
/// Most entries in one LoadTable frame (as long as a full LoadModel frame).
pub const MAX_LOAD_ENTRIES: usize = MAX_LOAD_POINTS * POINT_BYTES / TABLE_ENTRY_BYTES;
/// Entries of the cell table: one a cell, and the point count.
pub const TABLE_ENTRIES: usize = crate::search::grid::CELLS + 1;
/// Mask of a stored table entry.
pub const TABLE_ENTRY_MASK: u16 = (1 << 13) - 1;
/// Data bytes of a load request before its points: offset, count.
pub const LOAD_HEADER_BYTES: usize = 4;

/// LoadModel / LoadScan request data: offset, count, points.
pub fn load_request(offset: u16, points: &[FxPoint]) -> Vec<u8> {
    let mut out = Vec::with_capacity(4 + POINT_BYTES * points.len());
    put(&mut out, offset as u64, 2);
    put(&mut out, points.len() as u64, 2);
    for &p in points {
        out.extend_from_slice(&point_bytes(p));
    }
    out
}

/// LoadTable request data: offset, count, entries.
pub fn table_request(offset: u16, entries: &[u16]) -> Vec<u8> {
    let mut out = Vec::with_capacity(LOAD_HEADER_BYTES + TABLE_ENTRY_BYTES * entries.len());
    put(&mut out, offset as u64, 2);
    put(&mut out, entries.len() as u64, 2);
    for &e in entries {
        put(&mut out, e as u64, TABLE_ENTRY_BYTES);
    }
    out
}

/// LoadModel's word offset of the normal store: words `0..MAX_POINTS` are the model points,
/// `NORMALS_OFFSET + i` the normal of stored point `i` (`crate::surface::FxNormal`, packed
/// as a point).
pub const NORMALS_OFFSET: usize = MAX_POINTS;
/// LoadModel's words: the points, then their normals.
pub const MODEL_WORDS: usize = 2 * MAX_POINTS;

/// The requests (command, data) that upload a gridded model: LoadModel frames of its
/// points as stored (sorted by cell), LoadModel frames of their normals (`normals[i]` the
/// normal of stored point `i`, from word [`NORMALS_OFFSET`]), then LoadTable frames of its
/// whole cell table.
pub fn grid_upload(
    grid: &crate::search::grid::Grid,
    normals: &[crate::surface::FxNormal],
) -> Vec<(crate::protocol::Command, Vec<u8>)> {
    use crate::protocol::Command;
    assert_eq!(normals.len(), grid.points.len(), "one normal per stored model point");
    let points = grid.points.chunks(MAX_LOAD_POINTS).enumerate();
    let normals = normals.chunks(MAX_LOAD_POINTS).enumerate();
    let entries = grid.first.chunks(MAX_LOAD_ENTRIES).enumerate();
    points
        .map(|(k, c)| (Command::LoadModel, load_request((k * MAX_LOAD_POINTS) as u16, c)))
        .chain(
            normals.map(|(k, c)| (Command::LoadModel, load_request((NORMALS_OFFSET + k * MAX_LOAD_POINTS) as u16, c))),
        )
        .chain(entries.map(|(k, c)| (Command::LoadTable, table_request((k * MAX_LOAD_ENTRIES) as u16, c))))
        .collect()
}

/// The model digest a board reports after [`grid_upload`]'s requests (the first a LoadModel
/// at offset 0): what a host compares with Identify's to skip the upload.
pub fn grid_digest(grid: &crate::search::grid::Grid, normals: &[crate::surface::FxNormal]) -> u32 {
    grid_upload(grid, normals)
        .iter()
        .fold(crate::protocol::DIGEST_INIT, |d, (_, data)| crate::protocol::digest_update(d, data))
}
