//! The Verilated models in the build's archive (a table of each shim's entry points,
//! written by `build.rs`) and [`Core`], one instance of one of them: inputs and outputs as
//! packed `u64` words, clock, VCD.

use std::ffi::CString;
use std::os::raw::{c_char, c_int, c_void};
use std::path::{Path, PathBuf};

/// One Verilated model in the archive (a table of its shim's entry points).
pub(crate) struct Model {
    /// `neighbour_pipeline`, `weight_stage`, `board`, ... (`pficp_fpga::designs::DESIGNS`).
    pub(crate) design: &'static str,
    /// Lanes (0 for a design without lanes).
    pub(crate) lanes: usize,
    pub(crate) prefix: &'static str,
    pub(crate) verilog: &'static str,
    /// `u64` words of the packed input array.
    pub(crate) in_words: usize,
    /// Output ports in the order of the packed output array (one `u64` each).
    pub(crate) outputs: &'static [&'static str],
    pub(crate) out_words: usize,
    pub(crate) new: unsafe extern "C" fn() -> *mut c_void,
    pub(crate) free: unsafe extern "C" fn(*mut c_void),
    pub(crate) tick: unsafe extern "C" fn(*mut c_void, u64),
    pub(crate) trace_open: unsafe extern "C" fn(*mut c_void, *const c_char, u64) -> c_int,
    pub(crate) trace_flush: unsafe extern "C" fn(*mut c_void),
    pub(crate) trace_close: unsafe extern "C" fn(*mut c_void),
    pub(crate) set_inputs: unsafe extern "C" fn(*mut c_void, *const u64),
    pub(crate) get_outputs: unsafe extern "C" fn(*mut c_void, *mut u64),
}

pub(crate) mod ffi {
    use super::Model;
    use std::os::raw::{c_char, c_int, c_void};
    include!(concat!(env!("OUT_DIR"), "/models.rs"));
}
pub use ffi::BUILD_REPORT;

/// Lane counts with a Verilated neighbour pipeline: the build verilates 4 and 16 unless
/// `PFICP_SIM_LANES` says otherwise.
pub fn verilated_lanes() -> Vec<usize> {
    ffi::MODELS.iter().filter(|m| m.design == pficp_fpga::designs::NEIGHBOUR_PIPELINE.name).map(|m| m.lanes).collect()
}

/// Every Verilated model: (design, lanes, Verilator prefix), e.g. `("neighbour_pipeline", 16,
/// "Vnbr16")`; the designs without lanes have 0.
pub fn verilated_models() -> Vec<(&'static str, usize, &'static str)> {
    ffi::MODELS.iter().map(|m| (m.design, m.lanes, m.prefix)).collect()
}

/// A Verilated model with its own `VerilatedContext`, untyped (packed `u64` ports).
pub(crate) struct Core {
    pub(crate) model: &'static Model,
    pub(crate) h: *mut c_void,
    pub(crate) cycle: u64,
    pub(crate) trace: Option<PathBuf>,
}

impl Core {
    /// A fresh model of `design` with `lanes` lanes; its ports must be `in_words` input words
    /// and the outputs `outputs` (what the typed wrapper packs and unpacks).
    pub(crate) fn new(design: &str, lanes: usize, in_words: usize, outputs: &[&str]) -> Core {
        let model = ffi::MODELS.iter().find(|m| m.design == design && m.lanes == lanes).unwrap_or_else(|| {
            panic!(
                "no Verilated {design} model with {lanes} lanes (built: {:?}; rebuild with PFICP_SIM_LANES=...)",
                verilated_models()
            )
        });
        assert!(
            model.in_words == in_words && model.out_words == outputs.len() && model.outputs == outputs,
            "{}: the shim's ports ({} input words, outputs {:?}) are not the wrapper's ({in_words}, {outputs:?})",
            model.prefix,
            model.in_words,
            model.outputs
        );
        // SAFETY: the shim allocates and evaluates a fresh model.
        let h = unsafe { (model.new)() };
        assert!(!h.is_null());
        Core { model, h, cycle: 0, trace: None }
    }

    pub(crate) fn set_inputs<const N: usize>(&mut self, words: &[u64; N]) {
        debug_assert_eq!(N, self.model.in_words);
        // SAFETY: the array has the length the shim reads (checked in `new`).
        unsafe { (self.model.set_inputs)(self.h, words.as_ptr()) }
    }

    pub(crate) fn outputs<const N: usize>(&self) -> [u64; N] {
        debug_assert_eq!(N, self.model.out_words);
        let mut o = [0u64; N];
        // SAFETY: the array has the length the shim writes (checked in `new`).
        unsafe { (self.model.get_outputs)(self.h, o.as_mut_ptr()) };
        o
    }

    pub(crate) fn tick(&mut self) {
        self.cycle += 1;
        // SAFETY: valid handle.
        unsafe { (self.model.tick)(self.h, 10 * self.cycle) }
    }

    pub(crate) fn trace_to(&mut self, path: &Path) -> std::io::Result<()> {
        if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir)?;
        }
        let c = CString::new(path.as_os_str().as_encoded_bytes())
            .map_err(|_| std::io::Error::new(std::io::ErrorKind::InvalidInput, "NUL in the VCD path"))?;
        // SAFETY: valid handle and C string.
        if unsafe { (self.model.trace_open)(self.h, c.as_ptr(), 10 * self.cycle) } != 0 {
            self.trace = None;
            return Err(std::io::Error::other(format!("Verilator cannot open {}", path.display())));
        }
        self.trace = Some(path.to_path_buf());
        Ok(())
    }

    pub(crate) fn flush_trace(&mut self) {
        // SAFETY: valid handle.
        unsafe { (self.model.trace_flush)(self.h) }
    }

    pub(crate) fn close_trace(&mut self) {
        // SAFETY: valid handle.
        unsafe { (self.model.trace_close)(self.h) };
        self.trace = None;
    }
}

impl Drop for Core {
    fn drop(&mut self) {
        // SAFETY: the handle came from `new` and is freed once.
        unsafe { (self.model.free)(self.h) }
    }
}

// The handle is owned exclusively; Verilator models with separate contexts may move between
// threads.
unsafe impl Send for Core {}

/// The methods every wrapper has (on `self.core`).
macro_rules! verilated_common {
    ($ty:ident, $inputs:ty) => {
        impl $ty {
            /// The Verilator prefix of the model (`Vnbr16`, `Vweights`, `Vboard`).
            pub fn prefix(&self) -> &'static str {
                self.core.model.prefix
            }

            /// The Verilog file that was verilated.
            pub fn verilog_path(&self) -> &'static Path {
                Path::new(self.core.model.verilog)
            }

            /// One clock: clock low, eval, clock high (the rising edge), eval; the VCD, if
            /// open, gets both phases.
            pub fn tick(&mut self) {
                self.core.tick()
            }

            /// Apply the inputs and tick.
            pub fn step(&mut self, i: &$inputs) {
                self.set_inputs(i);
                self.tick();
            }

            /// Rising edges so far.
            pub fn cycle(&self) -> u64 {
                self.core.cycle
            }

            /// Write a VCD of every signal from now on (the current state at time
            /// `10 * cycle`, then both phases of every clock). Replaces an open trace.
            pub fn trace_to(&mut self, path: impl AsRef<Path>) -> std::io::Result<()> {
                self.core.trace_to(path.as_ref())
            }

            /// The open VCD, if any.
            pub fn trace_path(&self) -> Option<&Path> {
                self.core.trace.as_deref()
            }

            /// Flush the VCD to disk (it is also flushed when closed or dropped).
            pub fn flush_trace(&mut self) {
                self.core.flush_trace()
            }

            /// Close the VCD.
            pub fn close_trace(&mut self) {
                self.core.close_trace()
            }
        }

        impl fmt::Debug for $ty {
            fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.debug_struct(stringify!($ty))
                    .field("prefix", &self.core.model.prefix)
                    .field("cycle", &self.core.cycle)
                    .field("trace", &self.core.trace)
                    .finish()
            }
        }
    };
}
