//! The uploads: the model store (points and their normals), the cell table, the gridded
//! model in one go ([`BoardClient::load_grid`]), the scan store, and the sizes in use; each
//! frame acknowledged and its acknowledgement checked.

use super::{BoardClient, BoardError, BOARD_MAX_STORE_POINTS};
use pficp_fpga::common::format::FxPoint;
use pficp_fpga::protocol::layout::POINT_BYTES;
use pficp_fpga::protocol::messages::{
    load_request, parse_two_u16, table_request, two_u16, MessageError, MAX_LOAD_ENTRIES, MAX_LOAD_POINTS,
    NORMALS_OFFSET, TABLE_ENTRIES, TABLE_ENTRY_BYTES, TABLE_ENTRY_MASK,
};
use pficp_fpga::protocol::Command;
use pficp_fpga::search::grid::Grid;
use pficp_fpga::surface::FxNormal;

impl BoardClient {
    /// Write the model store from point 0, in frames of [`MAX_LOAD_POINTS`], each
    /// acknowledged; `progress(done, total)` after each. Sizes are not changed. A protocol
    /// 3 board searches the model through its cell table: use [`Self::load_grid`].
    pub fn load_model(&mut self, points: &[FxPoint], progress: impl FnMut(usize, usize)) -> Result<(), BoardError> {
        self.grid_order = None;
        self.load(Command::LoadModel, points, progress)
    }

    /// Write the cell table (protocol 3, LoadTable) from entry 0, in frames of
    /// [`MAX_LOAD_ENTRIES`], each acknowledged; `progress(done, total)` after each. At most
    /// [`TABLE_ENTRIES`] entries of 13 bits.
    pub fn load_table(&mut self, entries: &[u16], mut progress: impl FnMut(usize, usize)) -> Result<(), BoardError> {
        if entries.is_empty() || entries.len() > TABLE_ENTRIES {
            return Err(BoardError::Limit(format!(
                "a cell table of {} entries; the board holds 1 to {TABLE_ENTRIES}",
                entries.len()
            )));
        }
        if let Some(i) = entries.iter().position(|&e| e > TABLE_ENTRY_MASK) {
            return Err(BoardError::Limit(format!(
                "cell table entry {i} is {}; entries have 13 bits (at most {TABLE_ENTRY_MASK})",
                entries[i]
            )));
        }
        self.grid_order = None;
        let command = Command::LoadTable;
        progress(0, entries.len());
        let mut offset = 0;
        for chunk in entries.chunks(MAX_LOAD_ENTRIES) {
            let reply = self.transact(command, table_request(offset as u16, chunk), 4, 0, true)?;
            self.check_ack(command, &reply.data, offset, chunk.len())?;
            offset += chunk.len();
            progress(offset, entries.len());
        }
        Ok(())
    }

    /// Upload a gridded model (protocol 4): the points sorted by cell ([`Grid::points`],
    /// LoadModel), their normals (`normals[i]` the normal of stored point `i`, LoadModel from
    /// word [`NORMALS_OFFSET`]) then the cell table ([`Grid::first`], LoadTable): the
    /// requests of `messages::grid_upload`. `progress(done, total)` counts the data bytes of
    /// all three (6 a point or normal, 2 a table entry), so it rises once from 0 to the
    /// total. Afterwards the board's (stored) model indices map to the host's through
    /// [`Grid::order`] ([`Self::nearest_model`]). Sizes are not changed: the model size in
    /// use is `grid.points.len()`.
    pub fn load_grid(
        &mut self,
        grid: &Grid,
        normals: &[FxNormal],
        mut progress: impl FnMut(usize, usize),
    ) -> Result<(), BoardError> {
        if normals.len() != grid.points.len() {
            return Err(BoardError::Limit(format!(
                "{} normals for {} model points; the board takes one a point",
                normals.len(),
                grid.points.len()
            )));
        }
        let point_bytes = grid.points.len() * POINT_BYTES;
        let total = 2 * point_bytes + grid.first.len() * TABLE_ENTRY_BYTES;
        self.load_model(&grid.points, |done, _| progress(done * POINT_BYTES, total))?;
        self.load_at(Command::LoadModel, NORMALS_OFFSET, normals, |done, _| {
            if done > 0 {
                progress(point_bytes + done * POINT_BYTES, total)
            }
        })?;
        self.load_table(&grid.first, |done, _| {
            if done > 0 {
                progress(2 * point_bytes + done * TABLE_ENTRY_BYTES, total)
            }
        })?;
        self.grid_order = Some(grid.order.clone());
        Ok(())
    }

    fn check_ack(&self, command: Command, data: &[u8], offset: usize, count: usize) -> Result<(), BoardError> {
        let ack = parse_two_u16(data).map_err(|problem| BoardError::Reply { command, problem })?;
        if ack != (offset as u16, count as u16) {
            return Err(BoardError::Reply {
                command,
                problem: MessageError::Field {
                    field: "offset, count",
                    got: ((ack.0 as u64) << 16) | ack.1 as u64,
                    expected: ((offset as u64) << 16) | count as u64,
                },
            });
        }
        Ok(())
    }

    /// Write the scan store from point 0, as [`Self::load_model`].
    pub fn load_scan(&mut self, points: &[FxPoint], progress: impl FnMut(usize, usize)) -> Result<(), BoardError> {
        self.load(Command::LoadScan, points, progress)
    }

    fn load(
        &mut self,
        command: Command,
        points: &[FxPoint],
        progress: impl FnMut(usize, usize),
    ) -> Result<(), BoardError> {
        self.load_at(command, 0, points, progress)
    }

    /// Write `points` from word `start` (0 for points, [`NORMALS_OFFSET`] for normals).
    fn load_at(
        &mut self,
        command: Command,
        start: usize,
        points: &[FxPoint],
        mut progress: impl FnMut(usize, usize),
    ) -> Result<(), BoardError> {
        let what = match (command, start) {
            (Command::LoadModel, 0) => "model",
            (Command::LoadModel, _) => "model's normals",
            _ => "scan",
        };
        let max = self.max_points(command);
        if points.is_empty() || points.len() > max {
            return Err(BoardError::Limit(format!(
                "the {what} has {} points; the board holds 1 to {max}",
                points.len()
            )));
        }
        progress(0, points.len());
        let mut done = 0;
        for chunk in points.chunks(MAX_LOAD_POINTS) {
            let offset = start + done;
            let reply = self.transact(command, load_request(offset as u16, chunk), 4, 0, true)?;
            self.check_ack(command, &reply.data, offset, chunk.len())?;
            done += chunk.len();
            progress(done, points.len());
        }
        Ok(())
    }

    fn max_points(&self, command: Command) -> usize {
        let id = self.identity;
        match command {
            Command::LoadModel => id.map_or(BOARD_MAX_STORE_POINTS, |i| i.max_model as usize),
            _ => id.map_or(BOARD_MAX_STORE_POINTS, |i| i.max_scan as usize),
        }
        .min(BOARD_MAX_STORE_POINTS)
    }

    /// Set the numbers of model and scan points in use (1 to 4,096 each).
    pub fn set_sizes(&mut self, model: usize, scan: usize) -> Result<(), BoardError> {
        for (what, n, command) in [("model", model, Command::LoadModel), ("scan", scan, Command::LoadScan)] {
            if n == 0 || n > self.max_points(command) {
                return Err(BoardError::Limit(format!(
                    "{what} size {n}: the board holds 1 to {}",
                    self.max_points(command)
                )));
            }
        }
        let data = two_u16(model as u16, scan as u16);
        let reply = self.transact(Command::SetSizes, data.clone(), 4, 0, true)?;
        if reply.data != data {
            let got = parse_two_u16(&reply.data)
                .map_err(|problem| BoardError::Reply { command: Command::SetSizes, problem })?;
            return Err(BoardError::Reply {
                command: Command::SetSizes,
                problem: MessageError::Field {
                    field: "sizes",
                    got: ((got.0 as u64) << 16) | got.1 as u64,
                    expected: ((model as u64) << 16) | scan as u64,
                },
            });
        }
        self.sizes = (model as u16, scan as u16);
        Ok(())
    }
}
