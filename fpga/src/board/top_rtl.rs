//! `BoardTop<P>`: the FPGA's top level. Pins: `clock` (the oscillator, the design clock, no
//! DCM), `reset_n` (active-low button), `uart_rx` / `uart_tx` (the USB-serial bridge),
//! `leds` (0 heartbeat, 1 receive activity, 2 busy (answering, or the particle filter running), 3 last answer was an error).

use super::engine_rtl::CommandEngine;
use super::frame_rx_rtl::FrameReceiver;
use super::uart_rtl::UartRx;
use crate::board::BoardConfig;
use rust_hdl::prelude::*;

/// The board with a `P`-lane pipeline.
#[derive(LogicBlock)]
pub struct BoardTop<const P: usize> {
    /// The design clock.
    pub clock: Signal<In, Clock>,
    /// Reset, active low (asynchronous: synchronised here).
    pub reset_n: Signal<In, Bit>,
    /// Serial data from the host.
    pub uart_rx: Signal<In, Bit>,
    /// Serial data to the host.
    pub uart_tx: Signal<Out, Bit>,
    /// Status LEDs.
    pub leds: Signal<Out, Bits<4>>,
    reset_sync: [DFF<Bit>; 2],
    reset: Signal<Local, Bit>,
    heartbeat: DFF<Bits<27>>,
    rx_glow: DFF<Bits<22>>,
    uart_in: UartRx,
    receiver: FrameReceiver,
    engine: CommandEngine<P>,
}

impl<const P: usize> BoardTop<P> {
    /// The board as `config` says (its `lanes` must be `P`).
    pub fn new(config: &BoardConfig) -> Self {
        assert_eq!(config.lanes, P, "BoardTop<{P}> with a {}-lane config", config.lanes);
        if let Some(problem) = config.uart_problem() {
            panic!("BoardTop: {problem}");
        }
        BoardTop {
            clock: Default::default(),
            reset_n: Default::default(),
            uart_rx: Default::default(),
            uart_tx: Default::default(),
            leds: Default::default(),
            reset_sync: Default::default(),
            reset: Default::default(),
            heartbeat: Default::default(),
            rx_glow: Default::default(),
            uart_in: UartRx::new(config.bit_period()),
            receiver: Default::default(),
            engine: CommandEngine::new(config),
        }
    }
}

impl<const P: usize> Logic for BoardTop<P> {
    #[hdl_gen]
    fn update(&mut self) {
        dff_setup!(self, clock, heartbeat, rx_glow);
        for i in 0..2 {
            self.reset_sync[i].clock.next = self.clock.val();
        }
        self.uart_in.clock.next = self.clock.val();
        self.receiver.clock.next = self.clock.val();
        self.engine.clock.next = self.clock.val();
        // Power-up reads 0: the board starts in reset for two clocks.
        self.reset_sync[0].d.next = self.reset_n.val();
        self.reset_sync[1].d.next = self.reset_sync[0].q.val();
        self.reset.next = !self.reset_sync[1].q.val();
        self.uart_in.reset.next = self.reset.val();
        self.receiver.reset.next = self.reset.val();
        self.engine.reset.next = self.reset.val();

        self.uart_in.rx.next = self.uart_rx.val();
        self.receiver.byte_valid.next = self.uart_in.valid.val();
        self.receiver.rx_data.next = self.uart_in.data.val();
        self.receiver.engine_busy.next = self.engine.busy.val();
        self.engine.fr_we.next = self.receiver.wr_en.val();
        self.engine.fr_waddr.next = self.receiver.wr_addr.val();
        self.engine.fr_wdata.next = self.receiver.wr_data.val();
        self.engine.frame.next = self.receiver.frame.val();
        self.engine.status.next = self.receiver.status.val();
        self.engine.len.next = self.receiver.len.val();
        self.engine.cmd.next = self.receiver.cmd.val();
        self.engine.seq.next = self.receiver.seq.val();
        self.engine.busy_seen.next = self.receiver.busy_seen.val();
        self.uart_tx.next = self.engine.tx.val();

        self.heartbeat.d.next = self.heartbeat.q.val() + 1;
        if self.uart_in.active.val() {
            self.rx_glow.d.next = bits::<22>(0x3f_ffff);
        } else if self.rx_glow.q.val().any() {
            self.rx_glow.d.next = self.rx_glow.q.val() - 1;
        }
        self.leds.next = bit_cast::<4, 1>(self.heartbeat.q.val().get_bits::<1>(26))
            | (bit_cast::<4, 1>(self.rx_glow.q.val().get_bits::<1>(21)) << 1)
            | (bit_cast::<4, 1>((self.engine.busy.val() || self.engine.running.val()).into()) << 2)
            | (bit_cast::<4, 1>(self.engine.error.val().into()) << 3);
    }
}
