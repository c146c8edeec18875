//! What each protocol version allows the host to do with a board, in one table
//! ([`capabilities`]), and the one text of a refusal ([`refusal`]).
//!
//! - 1: the host-driven commands (Evaluate, Nearest), the model uploaded as it is (the
//!   brute-force search);
//! - 2: adds Run, Status and Result; the host-driven mode as version 1;
//! - 3: the model searched through a cell table; its costs are point-to-point distances,
//!   which this host no longer models: refused;
//! - 4 and 5: the model gridded with its normals, the costs surface residuals;
//! - 6: the Run of the on-board filter and its polish; the polish always solves for the
//!   scale: refused for the on-board mode, since this host holds a known scale on the board;
//! - [`VERSION`] (7): as 6, and the Run's polish holds the scale when asked
//!   ([`crate::protocol::run_request::SCALE_HELD`]).

use super::VERSION;

/// What one protocol version allows.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Capabilities {
    /// The host-driven mode (Evaluate and Nearest, the host's filter): 1, 2 and 4 to
    /// [`VERSION`].
    pub host_driven: bool,
    /// The model uploaded gridded with its normals (LoadModel, LoadTable), the costs
    /// surface residuals: from 4 on (a version 1 or 2 board gets the model as it is and
    /// searches it by brute force).
    pub grid_with_normals: bool,
    /// The on-board filter and its polish (Run), the polish holding a known scale:
    /// [`VERSION`] only.
    pub on_board_run: bool,
}

/// The capabilities of a board that speaks `version`.
pub fn capabilities(version: u16) -> Capabilities {
    Capabilities {
        host_driven: matches!(version, 1 | 2) || (4..=VERSION).contains(&version),
        grid_with_normals: version >= 4,
        on_board_run: version == VERSION,
    }
}

/// What the host asks of a board.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mode {
    /// The host-driven mode (`--host-driven`).
    HostDriven,
    /// The on-board filter and its polish.
    OnBoard,
}

/// Why a board of `version` cannot serve `mode`, or `None` when it can.
pub fn refusal(version: u16, mode: Mode) -> Option<String> {
    let c = capabilities(version);
    match mode {
        Mode::HostDriven if !c.host_driven => Some(format!(
            "the board speaks protocol version {version}, this host {VERSION} (1, 2 or 4 to {VERSION} for the host-driven mode; \
             regenerate a version 3 board)"
        )),
        Mode::OnBoard if !c.on_board_run => Some(format!(
            "the board speaks protocol version {version}, this host {VERSION} (the on-board filter and its polish \
             need {VERSION}; regenerate the board, or use --host-driven, which works with versions 1, 2 and 4 to \
             {VERSION})"
        )),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_table() {
        let host_driven: Vec<u16> = (0..=VERSION + 1).filter(|&v| capabilities(v).host_driven).collect();
        assert_eq!(host_driven, [1, 2].into_iter().chain(4..=VERSION).collect::<Vec<_>>());
        assert!(capabilities(4).grid_with_normals && !capabilities(3).grid_with_normals);
        assert!(capabilities(VERSION).on_board_run && !capabilities(VERSION - 1).on_board_run);
        assert!(refusal(3, Mode::HostDriven).is_some() && refusal(VERSION, Mode::HostDriven).is_none());
        assert!(refusal(VERSION - 1, Mode::OnBoard).is_some() && refusal(VERSION, Mode::OnBoard).is_none());
    }
}
