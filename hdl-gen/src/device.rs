//! Capacity of the target device, the Spartan-6 XC6SLX45-2FGG484 (DS160, UG384).

/// 6-input LUTs.
pub const LUT6: u64 = 27_288;
/// Slice flip-flops.
pub const FF: u64 = 54_576;
/// DSP48A1 slices.
pub const DSP48A1: u64 = 58;
/// 18 Kb block RAMs (RAMB16BWER; each can be split into two 9 Kb RAMB8BWER).
pub const RAMB16BWER: u64 = 116;
/// Slices.
pub const SLICES: u64 = 6_822;
/// CARRY4 chains: one per SLICEL/SLICEM, which are half of the slices (the other half are
/// SLICEX, without carry logic or wide multiplexers; UG384).
pub const CARRY4: u64 = SLICES / 2;
/// MUXF7: two per SLICEL/SLICEM (F7AMUX, F7BMUX).
pub const MUXF7: u64 = SLICES;
/// MUXF8: one per SLICEL/SLICEM (F8MUX).
pub const MUXF8: u64 = SLICES / 2;
/// User I/O pins of the FGG484 package.
pub const USER_IO: u64 = 316;
/// Global clock buffers.
pub const BUFG: u64 = 16;
/// Device name used in reports.
pub const NAME: &str = "Spartan-6 XC6SLX45-2FGG484";
