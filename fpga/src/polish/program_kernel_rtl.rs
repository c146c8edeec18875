//! PolishProgram's clocked logic: one `update` over the states of [`ProgramState`] (the ports,
//! registers, ROM and register file are in `program_rtl.rs`).

use super::*;
use crate::polish::program::{ADD_BITS, DIVISOR_BITS, FIELD_A, FIELD_B, FIELD_D, FIELD_K, FIELD_LAST, REG_BITS};

// Literals in the kernel (`#[hdl_gen]` takes no paths): the fields' positions, the kinds'
// codes (`crate::polish::program::kind`) and the units' widths.
const _: () = assert!(FIELD_D == 4 && FIELD_A == 10 && FIELD_B == 16 && FIELD_K == 22 && FIELD_LAST == 29);
const _: () = assert!(DIVISOR_BITS == 64 && ADD_BITS == 48 && REG_BITS == 128);
const _: () = {
    use crate::polish::program::kind::*;
    assert!(
        ADD == 0
            && SUB == 1
            && MUL == 2
            && DIV == 3
            && SHR == 4
            && CONST == 5
            && CLAMP == 6
            && STOP_BELOW == 7
            && SAT == 8
    );
};

impl Logic for PolishProgram {
    #[hdl_gen]
    fn update(&mut self) {
        dff_setup!(
            self, clock, state, ret, pc, ins, x, y, acc, car, sign, sa, sb, ia, ib, ci, mdone, rem, lo, lo_c, neg, cnt,
            fail, pend, pend_addr, add_v
        );
        self.rf.read_clock.next = self.clock.val();
        self.rf.write_clock.next = self.clock.val();
        self.prog.clock.next = self.clock.val();
        self.kind.next = self.ins.q.val().get_bits::<4>(0);
        self.opb.next = self.rf.read_data.val();
        self.read_data.next = self.rf.read_data.val();
        self.busy.next = self.state.q.val() != ProgramState::Idle;
        self.failed.next = self.fail.q.val();
        self.acc_sra.next = (self.acc.q.val() >> 1).replace_bit(127, self.acc.q.val().get_bit(127));
        self.acc_sra8.next = self.acc.q.val() >> 8;
        if self.acc.q.val().get_bit(127) {
            self.acc_sra8.next = (self.acc.q.val() >> 8) | ((!bits::<128>(0)) << 120);
        }

        // The adder, from registers only.
        self.alu_a.next = 0.into();
        if self.sa.q.val() == 0 {
            self.alu_a.next = self.x.q.val();
        }
        if self.sa.q.val() == 1 {
            self.alu_a.next = self.x.q.val() << 1;
        }
        if self.sa.q.val() == 2 {
            self.alu_a.next = self.acc.q.val();
        }
        if self.ia.q.val() {
            self.alu_a.next = !self.alu_a.val();
        }
        self.alu_b.next = 0.into();
        if self.sb.q.val() == 0 {
            self.alu_b.next = self.opb.val();
        }
        if self.sb.q.val() == 1 {
            self.alu_b.next = self.x.q.val();
        }
        if self.sb.q.val() == 3 {
            self.alu_b.next = self.x.q.val() << 1;
        }
        if self.ib.q.val() {
            self.alu_b.next = !self.alu_b.val();
        }
        self.s0.next = bit_cast::<33, 32>(self.alu_a.val().get_bits::<32>(0))
            + bit_cast::<33, 32>(self.alu_b.val().get_bits::<32>(0))
            + bit_cast::<33, 1>(self.ci.q.val().into());
        self.s1.next = bit_cast::<33, 32>(self.alu_a.val().get_bits::<32>(32))
            + bit_cast::<33, 32>(self.alu_b.val().get_bits::<32>(32))
            + bit_cast::<33, 1>(self.car.q.val().get_bits::<1>(0));
        self.s2.next = bit_cast::<33, 32>(self.alu_a.val().get_bits::<32>(64))
            + bit_cast::<33, 32>(self.alu_b.val().get_bits::<32>(64))
            + bit_cast::<33, 1>(self.car.q.val().get_bits::<1>(1));
        self.s3.next = bit_cast::<33, 32>(self.alu_a.val().get_bits::<32>(96))
            + bit_cast::<33, 32>(self.alu_b.val().get_bits::<32>(96))
            + bit_cast::<33, 1>(self.car.q.val().get_bits::<1>(2));
        self.sum.next = bit_cast::<128, 32>(self.s0.val().get_bits::<32>(0))
            | (bit_cast::<128, 32>(self.s1.val().get_bits::<32>(0)) << 32)
            | (bit_cast::<128, 32>(self.s2.val().get_bits::<32>(0)) << 64)
            | (bit_cast::<128, 32>(self.s3.val().get_bits::<32>(0)) << 96);
        self.carries.next = bit_cast::<3, 1>(self.s0.val().get_bits::<1>(32))
            | (bit_cast::<3, 1>(self.s1.val().get_bits::<1>(32)) << 1)
            | (bit_cast::<3, 1>(self.s2.val().get_bits::<1>(32)) << 2);

        // The multiplier for the next clock: the second operand entering (no bit below),
        // else y shifted two bits and its last bit out below.
        self.ny.next = (self.y.q.val() >> 2)
            .replace_bit(127, self.y.q.val().get_bit(127))
            .replace_bit(126, self.y.q.val().get_bit(127));
        self.my.next = self.ny.val();
        self.myp.next = self.y.q.val().get_bit(1);
        if self.state.q.val() == ProgramState::Exec {
            self.my.next = self.opb.val();
            self.myp.next = false;
        }
        self.my_ones.next = !(!self.my.val()).any();
        self.my_zeros.next = !self.my.val().any();
        // A negative digit (-1 or -2: the top bit set, not all three).
        self.my_neg.next = self.my.val().get_bit(1) && !(self.my.val().get_bit(0) && self.myp.val());

        // The divider: the remainder shifted, the dividend's next bit in (the dividend
        // shifts out of `acc`).
        self.rem2.next = (self.rem.q.val() << 1) | bit_cast::<65, 1>(self.acc.q.val().get_bits::<1>(127));
        // (The complements in signals of their own width: Verilog would widen the operand
        // of `~` to the sum's width first.)
        self.not_y_lo.next = !self.y.q.val().get_bits::<33>(0);
        self.not_y_hi.next = !bit_cast::<32, 31>(self.y.q.val().get_bits::<31>(33));
        self.div_lo.next =
            bit_cast::<34, 33>(self.rem2.val().get_bits::<33>(0)) + bit_cast::<34, 33>(self.not_y_lo.val()) + 1;
        self.div_hi.next = bit_cast::<33, 32>(self.rem2.val().get_bits::<32>(33))
            + bit_cast::<33, 32>(self.not_y_hi.val())
            + bit_cast::<33, 1>(self.lo_c.q.val().into());
        self.wide.next = self.y.q.val().get_bits::<64>(64).any();
        // The divisor goes (the remainder becomes the trial's difference).
        self.div_sub.next = self.div_hi.val().get_bit(32) && !self.wide.val();
        // The next quotient bit's low half, for either outcome of this one: from the
        // difference's low half (`lo`) or the shifted remainder's, the dividend's next bit
        // (`acc`'s bit 126) in.
        self.div_next_sub.next = bit_cast::<34, 33>(
            (bit_cast::<33, 32>(self.lo.q.val().get_bits::<32>(0)) << 1)
                | bit_cast::<33, 1>(self.acc.q.val().get_bits::<1>(126)),
        ) + bit_cast::<34, 33>(self.not_y_lo.val())
            + 1;
        self.div_next_keep.next = bit_cast::<34, 33>(
            (bit_cast::<33, 32>(self.rem2.val().get_bits::<32>(0)) << 1)
                | bit_cast::<33, 1>(self.acc.q.val().get_bits::<1>(126)),
        ) + bit_cast::<34, 33>(self.not_y_lo.val())
            + 1;
        self.add_sum.next = self.rf.read_data.val().get_bits::<48>(0) + self.add_v.q.val();

        self.rf.read_address.next = self.ins.q.val().get_bits::<6>(16);
        self.rf.write_enable.next = false;
        self.rf.write_address.next = self.ins.q.val().get_bits::<6>(4);
        self.rf.write_data.next = self.acc.q.val();

        self.sel_a.next = 0.into();
        self.sel_b.next = 2.into();
        self.inva.next = false;
        self.invb.next = false;
        self.cin.next = false;
        self.issue.next = false;
        self.then.next = ProgramState::Write;
        self.pend.d.next = false;
        match self.state.q.val() {
            ProgramState::Idle => {
                self.rf.read_address.next = self.read_addr.val();
                if self.add.val() {
                    self.rf.read_address.next = self.add_addr.val();
                }
                if self.load.val() {
                    self.rf.write_enable.next = true;
                    self.rf.write_address.next = self.load_addr.val();
                    self.rf.write_data.next = self.load_data.val();
                }
                self.pend.d.next = self.add.val();
                if self.add.val() {
                    self.pend_addr.d.next = self.add_addr.val();
                    self.add_v.d.next = self.add_data.val();
                }
                if self.pend.q.val() {
                    self.rf.write_enable.next = true;
                    self.rf.write_address.next = self.pend_addr.q.val();
                    self.rf.write_data.next = bit_cast::<128, 48>(self.add_sum.val());
                    if self.add_sum.val().get_bit(47) {
                        self.rf.write_data.next = bit_cast::<128, 48>(self.add_sum.val()) | ((!bits::<128>(0)) << 48);
                    }
                }
                if self.go.val() {
                    self.pc.d.next = self.entry.val();
                    self.fail.d.next = false;
                    self.state.d.next = ProgramState::Fetch;
                }
            }
            ProgramState::Fetch => {
                self.rf.read_address.next = self.prog.data.val().get_bits::<6>(10);
                self.ins.d.next = self.prog.data.val();
                self.state.d.next = ProgramState::Operand;
            }
            ProgramState::Operand => {
                self.x.d.next = self.rf.read_data.val();
                self.state.d.next = ProgramState::Exec;
            }
            ProgramState::Exec => {
                self.cnt.d.next = bit_cast::<8, 7>(self.ins.q.val().get_bits::<7>(22));
                // x + B: an add; a subtract's x + ~B + 1; a clamp's and a saturation's test
                // x + ~B = x - B - 1; a stop's 2 x + ~B + 1; a shift's x + 0.
                self.sel_b.next = 0.into();
                self.issue.next = true;
                if self.kind.val() == 1 {
                    self.invb.next = true;
                    self.cin.next = true;
                }
                if self.kind.val() == 2 {
                    // A product: acc = 0, the multiplier's first bit.
                    self.issue.next = false;
                    self.acc.d.next = 0.into();
                    self.car.d.next = 0.into();
                    self.y.d.next = self.opb.val();
                    self.state.d.next = ProgramState::Mul;
                }
                if self.kind.val() == 3 {
                    self.issue.next = false;
                    self.y.d.next = self.opb.val();
                    self.state.d.next = ProgramState::ShiftLeft;
                }
                if self.kind.val() == 4 {
                    self.sel_b.next = 2.into();
                    self.then.next = ProgramState::Round;
                }
                if self.kind.val() == 5 {
                    self.issue.next = false;
                    self.x.d.next = bit_cast::<128, 6>(self.ins.q.val().get_bits::<6>(10));
                    self.state.d.next = ProgramState::ShiftLeft;
                }
                if (self.kind.val() == 6) || (self.kind.val() == 8) {
                    self.invb.next = true;
                    self.then.next = ProgramState::ClampTest;
                }
                if self.kind.val() == 7 {
                    self.sel_a.next = 1.into();
                    self.invb.next = true;
                    self.cin.next = true;
                    self.then.next = ProgramState::StopTest;
                }
            }
            ProgramState::Alu => {
                // The result, its pending carries, and the 129-bit result's sign from the
                // operands' and the carry out of the top (at most one carry leaves the top
                // over the add and its flush).
                self.acc.d.next = self.sum.val();
                self.car.d.next = self.carries.val();
                self.sign.d.next =
                    self.alu_a.val().get_bit(127) ^ self.alu_b.val().get_bit(127) ^ self.s3.val().get_bit(32);
                self.sa.d.next = 2.into();
                self.sb.d.next = 2.into();
                self.ia.d.next = false;
                self.ib.d.next = false;
                self.ci.d.next = false;
                self.state.d.next = ProgramState::Flush;
            }
            ProgramState::Flush => {
                // acc + 0 with the pending carries, until none is left.
                if self.car.q.val().any() {
                    self.acc.d.next = self.sum.val();
                    self.car.d.next = self.carries.val();
                    self.sign.d.next = self.sign.q.val() ^ self.s3.val().get_bit(32);
                } else {
                    self.state.d.next = self.ret.q.val();
                }
            }
            ProgramState::Mul => {
                // This clock's bit (set by the clock before): acc + x, acc + ~x + 1 (the
                // rest all ones) or acc + 0, the segment carries pending.
                if self.mdone.q.val() {
                    self.sa.d.next = 2.into();
                    self.sb.d.next = 2.into();
                    self.ib.d.next = false;
                    self.ci.d.next = false;
                    self.ret.d.next = ProgramState::Round;
                    self.state.d.next = ProgramState::Flush;
                } else {
                    self.acc.d.next = self.sum.val();
                    self.car.d.next = self.carries.val();
                    self.x.d.next = self.x.q.val() << 2;
                    self.y.d.next = self.ny.val();
                }
            }
            ProgramState::Round => {
                if (self.cnt.q.val() == 1) && (self.kind.val() == 2) {
                    // A product's last step, u = acc: (u >> 1) + (u & 1).
                    self.acc.d.next = self.acc_sra.val();
                    self.sel_a.next = 2.into();
                    self.cin.next = self.acc.q.val().get_bit(0);
                    self.issue.next = true;
                } else if self.cnt.q.val() > 8 {
                    self.cnt.d.next = self.cnt.q.val() - 8;
                    self.acc.d.next = self.acc_sra8.val();
                } else if self.cnt.q.val().any() {
                    self.cnt.d.next = self.cnt.q.val() - 1;
                    self.acc.d.next = self.acc_sra.val();
                } else {
                    self.state.d.next = ProgramState::Write;
                }
            }
            ProgramState::ShiftLeft => {
                if self.cnt.q.val() > 7 {
                    self.cnt.d.next = self.cnt.q.val() - 8;
                    self.x.d.next = self.x.q.val() << 8;
                } else if self.cnt.q.val().any() {
                    self.cnt.d.next = self.cnt.q.val() - 1;
                    self.x.d.next = self.x.q.val() << 1;
                } else {
                    // A constant: x + 0; a dividend's magnitude: x or ~x + 1.
                    self.issue.next = true;
                    if self.kind.val() == 3 {
                        self.neg.d.next = self.x.q.val().get_bit(127);
                        self.inva.next = self.x.q.val().get_bit(127);
                        self.cin.next = self.x.q.val().get_bit(127);
                        self.then.next = ProgramState::DivStart;
                    }
                }
            }
            ProgramState::DivStart => {
                self.rem.d.next = 0.into();
                self.cnt.d.next = 128.into();
                self.state.d.next = ProgramState::DivSkip;
            }
            ProgramState::DivSkip => {
                // Leading zeros of the dividend with the remainder zero and a divisor from 1
                // to 2^64 - 1: eight quotient bits of zero a clock, the remainder staying
                // zero (at least one bit left for `DivHi`'s sign).
                if (self.cnt.q.val() > 8)
                    && !self.acc.q.val().get_bits::<8>(120).any()
                    && self.y.q.val().get_bits::<64>(0).any()
                    && !self.wide.val()
                {
                    self.cnt.d.next = self.cnt.q.val() - 8;
                    self.acc.d.next = self.acc.q.val() << 8;
                } else {
                    self.state.d.next = ProgramState::DivLo;
                }
            }
            ProgramState::DivLo => {
                self.lo.d.next = self.div_lo.val().get_bits::<33>(0);
                self.lo_c.d.next = self.div_lo.val().get_bit(33);
                self.state.d.next = ProgramState::DivHi;
            }
            ProgramState::DivHi => {
                // No borrow: the divisor goes, the quotient bit is 1 (always, for a divisor
                // wider than 64 bits: a quotient of all ones, as for zero); the next bit's
                // low half is ready for either outcome, so the next bit is `DivHi` again.
                // After the last bit, the quotient's sign: acc or ~acc + 1.
                self.cnt.d.next = self.cnt.q.val() - 1;
                if self.cnt.q.val() == 1 {
                    self.sel_a.next = 2.into();
                    self.inva.next = self.neg.q.val();
                    self.cin.next = self.neg.q.val();
                    self.issue.next = true;
                }
                self.rem.d.next = self.rem2.val();
                self.lo.d.next = self.div_next_keep.val().get_bits::<33>(0);
                self.lo_c.d.next = self.div_next_keep.val().get_bit(33);
                self.acc.d.next = self.acc.q.val() << 1;
                if self.div_hi.val().get_bit(32) || self.wide.val() {
                    self.acc.d.next = (self.acc.q.val() << 1) | bits::<128>(1);
                }
                if self.div_sub.val() {
                    self.rem.d.next = (bit_cast::<65, 32>(self.div_hi.val().get_bits::<32>(0)) << 33)
                        | bit_cast::<65, 33>(self.lo.q.val());
                    self.lo.d.next = self.div_next_sub.val().get_bits::<33>(0);
                    self.lo_c.d.next = self.div_next_sub.val().get_bit(33);
                }
            }
            ProgramState::ClampTest => {
                // x - B - 1 is not negative: x > B, the result is 0 + B. Else the low bound's
                // test: x + B (a saturation's x + B + 1) below zero.
                self.issue.next = true;
                self.sel_a.next = 3.into();
                self.sel_b.next = 0.into();
                if self.sign.q.val() {
                    self.sel_a.next = 0.into();
                    self.cin.next = self.kind.val() == 8;
                    self.then.next = ProgramState::ClampLow;
                }
            }
            ProgramState::ClampLow => {
                // Below the low bound: the result is 0 + ~B + 1 = -B (a saturation's ~B);
                // else x + 0.
                self.issue.next = true;
                if self.sign.q.val() {
                    self.sel_a.next = 3.into();
                    self.sel_b.next = 0.into();
                    self.invb.next = true;
                    self.cin.next = self.kind.val() != 8;
                }
            }
            ProgramState::StopTest => {
                if self.sign.q.val() {
                    self.fail.d.next = true;
                    self.state.d.next = ProgramState::Idle;
                } else if self.ins.q.val().get_bit(29) {
                    self.state.d.next = ProgramState::Idle;
                } else {
                    self.pc.d.next = self.pc.q.val() + 1;
                    self.state.d.next = ProgramState::Fetch;
                }
            }
            ProgramState::Write => {
                self.rf.write_enable.next = true;
                if self.ins.q.val().get_bit(29) {
                    self.state.d.next = ProgramState::Idle;
                } else {
                    self.pc.d.next = self.pc.q.val() + 1;
                    self.state.d.next = ProgramState::Fetch;
                }
            }
        }
        // An issued add: its controls for the next clock's `Alu`.
        if self.issue.val() {
            self.sa.d.next = self.sel_a.val();
            self.sb.d.next = self.sel_b.val();
            self.ia.d.next = self.inva.val();
            self.ib.d.next = self.invb.val();
            self.ci.d.next = self.cin.val();
            self.ret.d.next = self.then.val();
            self.state.d.next = ProgramState::Alu;
        }
        // Entering or in a product: the next clock's multiplier bit.
        if ((self.state.q.val() == ProgramState::Exec) && (self.kind.val() == 2))
            || ((self.state.q.val() == ProgramState::Mul) && !self.mdone.q.val())
        {
            // Booth's digit of the next clock's two bits and the bit below: 0, x, 2 x, -x
            // (~x + 1) or -2 x; done once the rest gives only zero digits.
            self.mdone.d.next = (self.my_zeros.val() && !self.myp.val()) || (self.my_ones.val() && self.myp.val());
            self.sa.d.next = 2.into();
            self.sb.d.next = 2.into();
            if self.my.val().get_bit(0) != self.myp.val() {
                self.sb.d.next = 1.into();
            } else if self.my.val().get_bit(1) != self.my.val().get_bit(0) {
                self.sb.d.next = 3.into();
            }
            self.ia.d.next = false;
            self.ib.d.next = self.my_neg.val();
            self.ci.d.next = self.my_neg.val();
        }
        if self.reset.val() {
            self.state.d.next = ProgramState::Idle;
            self.car.d.next = 0.into();
            self.fail.d.next = false;
            self.pend.d.next = false;
        }
        // The ROM reads at the next program counter: the word at `pc` is there in `fetch`.
        self.prog.address.next = self.pc.d.val();
    }
}
