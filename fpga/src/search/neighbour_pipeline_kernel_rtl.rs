//! The neighbour pipeline's clocked logic: one `update` over its stages (the struct and its
//! registers are in `neighbour_pipeline_rtl.rs`).

use super::*;

impl<const P: usize> Logic for NeighbourPipeline<P> {
    #[hdl_gen]
    fn update(&mut self) {
        dff_setup!(
            self,
            clock,
            run,
            last_taken,
            l1,
            l2,
            pq_rd,
            pq_wr,
            pq_n,
            lk_have,
            lk_q,
            lk_last,
            lk_slot,
            lk_x0,
            lk_x1,
            rd_valid,
            rd_in_a,
            rd_in_b,
            rd_last,
            rd_slast,
            rd_q,
            rq_rd,
            rq_wr,
            rq_n,
            is_have,
            is_addr,
            is_end,
            is_av,
            is_baddr,
            is_bend,
            is_bv,
            is_last,
            is_slast,
            is_q,
            c0_valid,
            c0_last,
            c0_slast,
            c0_q,
            t4,
            u4,
            t5,
            acc_used,
            acc,
            fin,
            cost_acc,
            nn_valid_r,
            nn_index_r,
            nn_dist_r,
            nn_point_r,
            cost_valid_r,
            cost_r
        );
        for j in 0..4 {
            self.pq_x[j].clock.next = self.clock.val();
            self.pq_x[j].d.next = self.pq_x[j].q.val();
            self.pq_l[j].clock.next = self.clock.val();
            self.pq_l[j].d.next = self.pq_l[j].q.val();
            self.rq_alo[j].clock.next = self.clock.val();
            self.rq_alo[j].d.next = self.rq_alo[j].q.val();
            self.rq_ahi[j].clock.next = self.clock.val();
            self.rq_ahi[j].d.next = self.rq_ahi[j].q.val();
            self.rq_blo[j].clock.next = self.clock.val();
            self.rq_blo[j].d.next = self.rq_blo[j].q.val();
            self.rq_bhi[j].clock.next = self.clock.val();
            self.rq_bhi[j].d.next = self.rq_bhi[j].q.val();
            self.rq_av[j].clock.next = self.clock.val();
            self.rq_av[j].d.next = self.rq_av[j].q.val();
            self.rq_bv[j].clock.next = self.clock.val();
            self.rq_bv[j].d.next = self.rq_bv[j].q.val();
            self.rq_last[j].clock.next = self.clock.val();
            self.rq_last[j].d.next = self.rq_last[j].q.val();
            self.rq_slast[j].clock.next = self.clock.val();
            self.rq_slast[j].d.next = self.rq_slast[j].q.val();
            self.rq_q[j].clock.next = self.clock.val();
            self.rq_q[j].d.next = self.rq_q[j].q.val();
            self.lk_mask[j].clock.next = self.clock.val();
            self.lk_mask[j].d.next = self.lk_mask[j].q.val();
        }
        for k in 0..3 {
            self.lk_vy[k].clock.next = self.clock.val();
            self.lk_vy[k].d.next = self.lk_vy[k].q.val();
            self.lk_vz[k].clock.next = self.clock.val();
            self.lk_vz[k].d.next = self.lk_vz[k].q.val();
            self.lk_y[k].clock.next = self.clock.val();
            self.lk_y[k].d.next = self.lk_y[k].q.val();
            self.lk_z[k].clock.next = self.clock.val();
            self.lk_z[k].d.next = self.lk_z[k].q.val();
        }
        for k in 0..10 {
            self.ctl_v[k].clock.next = self.clock.val();
            self.ctl_l[k].clock.next = self.clock.val();
            self.ctl_s[k].clock.next = self.clock.val();
            self.ctl_q[k].clock.next = self.clock.val();
        }
        for j in 0..8 {
            self.t1[j].clock.next = self.clock.val();
            self.u1[j].clock.next = self.clock.val();
        }
        for j in 0..4 {
            self.t2[j].clock.next = self.clock.val();
            self.u2[j].clock.next = self.clock.val();
        }
        for j in 0..2 {
            self.t3[j].clock.next = self.clock.val();
            self.u3[j].clock.next = self.clock.val();
        }
        self.transform.clock.next = self.clock.val();
        self.lo_a.read_clock.next = self.clock.val();
        self.lo_a.write_clock.next = self.clock.val();
        self.hi_a.read_clock.next = self.clock.val();
        self.hi_a.write_clock.next = self.clock.val();
        self.lo_b.read_clock.next = self.clock.val();
        self.lo_b.write_clock.next = self.clock.val();
        self.hi_b.read_clock.next = self.clock.val();
        self.hi_b.write_clock.next = self.clock.val();
        for b in 0..P {
            self.lanes[b].clock.next = self.clock.val();
            self.lanes[b].model_we.next = self.model_we.val();
            self.lanes[b].model_waddr.next = self.model_waddr.val();
            self.lanes[b].model_wdata.next = self.model_wdata.val();
            // The B lanes' banks: the model RAM's second copy, written by the same writes.
            self.lanes_b[b].clock.next = self.clock.val();
            self.lanes_b[b].model_we.next = self.model_we.val();
            self.lanes_b[b].model_waddr.next = self.model_waddr.val();
            self.lanes_b[b].model_wdata.next = self.model_wdata.val();
        }
        // Status and the scan input: room in the point queue for the points in the transform.
        if self.transform.t1_valid.val() && self.transform.t2_valid.val() {
            self.ready.next = self.pq_n.q.val() < 2;
        } else if self.transform.t1_valid.val() || self.transform.t2_valid.val() {
            self.ready.next = self.pq_n.q.val() < 3;
        } else {
            self.ready.next = self.pq_n.q.val() < 4;
        }
        self.ready.next = self.ready.val() && self.run.q.val() && !self.last_taken.q.val();
        self.take.next = self.ready.val() && self.scan_valid.val();
        self.scan_ready.next = self.ready.val();
        self.busy.next = self.run.q.val();
        // Transform (pose latched with an honoured start), the last flag beside it.
        self.transform.load.next = !self.run.q.val() && self.start.val();
        self.transform.pose.next = self.pose.val();
        self.transform.take.next = self.take.val();
        self.transform.point.next = self.scan_data.val();
        self.l1.d.next = self.take.val() && self.scan_last.val();
        self.l2.d.next = self.l1.q.val();
        // Cell table: two copies of `lo[c] = first[c]` and `hi[c] = first[c + 1]`.
        self.taddr_m1.next = self.table_waddr.val() - 1;
        self.lo_a.write_address.next = self.table_waddr.val().get_bits::<12>(0);
        self.lo_a.write_data.next = self.table_wdata.val();
        self.lo_a.write_enable.next = self.table_we.val() && !self.table_waddr.val().get_bit(12);
        self.lo_b.write_address.next = self.table_waddr.val().get_bits::<12>(0);
        self.lo_b.write_data.next = self.table_wdata.val();
        self.lo_b.write_enable.next = self.table_we.val() && !self.table_waddr.val().get_bit(12);
        self.hi_a.write_address.next = self.taddr_m1.val().get_bits::<12>(0);
        self.hi_a.write_data.next = self.table_wdata.val();
        self.hi_a.write_enable.next =
            self.table_we.val() && (self.table_waddr.val() != 0) && !self.taddr_m1.val().get_bit(12);
        self.hi_b.write_address.next = self.taddr_m1.val().get_bits::<12>(0);
        self.hi_b.write_data.next = self.table_wdata.val();
        self.hi_b.write_enable.next =
            self.table_we.val() && (self.table_waddr.val() != 0) && !self.taddr_m1.val().get_bit(12);
        // Point queue head and its cells: per axis `u = (c >> 10) + 32` (the cell is u - 24).
        self.pq_head.next = self.pq_x[0].q.val();
        self.pq_head_l.next = self.pq_l[0].q.val();
        for j in 1..4 {
            if self.pq_rd.q.val() == self.qid[j].val() {
                self.pq_head.next = self.pq_x[j].q.val();
                self.pq_head_l.next = self.pq_l[j].q.val();
            }
        }
        for k in 0..3 {
            self.hu[k].next = self.pq_head.val().get_bits::<6>(16 * k + 10) ^ self.c_off.val();
        }
        // x: 0 <= k_x + 1 and k_x - 1 <= 15; row y (z) = k + d inside 0..=15.
        self.h_vx.next = (self.hu[0].val() >= 23) && (self.hu[0].val() <= 40);
        self.h_vy[0].next = self.h_vx.val() && (self.hu[1].val() >= 25) && (self.hu[1].val() <= 40);
        self.h_vy[1].next = self.h_vx.val() && (self.hu[1].val() >= 24) && (self.hu[1].val() <= 39);
        self.h_vy[2].next = self.h_vx.val() && (self.hu[1].val() >= 23) && (self.hu[1].val() <= 38);
        self.h_vz[0].next = (self.hu[2].val() >= 25) && (self.hu[2].val() <= 40);
        self.h_vz[1].next = (self.hu[2].val() >= 24) && (self.hu[2].val() <= 39);
        self.h_vz[2].next = (self.hu[2].val() >= 23) && (self.hu[2].val() <= 38);
        // Slots 0..3 (rows (dz, dy)): (-1, -1) (-1, 0) | (-1, 1) (0, -1) | (0, 1) (1, -1) |
        // (1, 0) (1, 1); slot 4 is the centre row.
        self.h_mask[0].next = self.h_vz[0].val() && (self.h_vy[0].val() || self.h_vy[1].val());
        self.h_mask[1].next = (self.h_vz[0].val() && self.h_vy[2].val()) || (self.h_vz[1].val() && self.h_vy[0].val());
        self.h_mask[2].next = (self.h_vz[1].val() && self.h_vy[2].val()) || (self.h_vz[2].val() && self.h_vy[0].val());
        self.h_mask[3].next = self.h_vz[2].val() && (self.h_vy[1].val() || self.h_vy[2].val());
        self.h_first.next = 4.into();
        if self.h_mask[3].val() {
            self.h_first.next = 3.into();
        }
        if self.h_mask[2].val() {
            self.h_first.next = 2.into();
        }
        if self.h_mask[1].val() {
            self.h_first.next = 1.into();
        }
        if self.h_mask[0].val() {
            self.h_first.next = 0.into();
        }
        // Lookup: the current slot's rows A and B.
        self.ra_y.next = self.lk_y[1].q.val();
        self.ra_z.next = self.lk_z[1].q.val();
        self.ra_in.next = self.lk_vy[1].q.val() && self.lk_vz[1].q.val();
        self.rb_y.next = self.lk_y[1].q.val();
        self.rb_z.next = self.lk_z[1].q.val();
        self.rb_in.next = false;
        if self.lk_slot.q.val() == 0 {
            self.ra_y.next = self.lk_y[0].q.val();
            self.ra_z.next = self.lk_z[0].q.val();
            self.ra_in.next = self.lk_vy[0].q.val() && self.lk_vz[0].q.val();
            self.rb_y.next = self.lk_y[1].q.val();
            self.rb_z.next = self.lk_z[0].q.val();
            self.rb_in.next = self.lk_vy[1].q.val() && self.lk_vz[0].q.val();
        } else if self.lk_slot.q.val() == 1 {
            self.ra_y.next = self.lk_y[2].q.val();
            self.ra_z.next = self.lk_z[0].q.val();
            self.ra_in.next = self.lk_vy[2].q.val() && self.lk_vz[0].q.val();
            self.rb_y.next = self.lk_y[0].q.val();
            self.rb_z.next = self.lk_z[1].q.val();
            self.rb_in.next = self.lk_vy[0].q.val() && self.lk_vz[1].q.val();
        } else if self.lk_slot.q.val() == 2 {
            self.ra_y.next = self.lk_y[2].q.val();
            self.ra_z.next = self.lk_z[1].q.val();
            self.ra_in.next = self.lk_vy[2].q.val() && self.lk_vz[1].q.val();
            self.rb_y.next = self.lk_y[0].q.val();
            self.rb_z.next = self.lk_z[2].q.val();
            self.rb_in.next = self.lk_vy[0].q.val() && self.lk_vz[2].q.val();
        } else if self.lk_slot.q.val() == 3 {
            self.ra_y.next = self.lk_y[1].q.val();
            self.ra_z.next = self.lk_z[2].q.val();
            self.ra_in.next = self.lk_vy[1].q.val() && self.lk_vz[2].q.val();
            self.rb_y.next = self.lk_y[2].q.val();
            self.rb_z.next = self.lk_z[2].q.val();
            self.rb_in.next = self.lk_vy[2].q.val() && self.lk_vz[2].q.val();
        }
        self.lo_a.read_address.next = (bit_cast::<12, 4>(self.ra_z.val()) << 8)
            | (bit_cast::<12, 4>(self.ra_y.val()) << 4)
            | bit_cast::<12, 4>(self.lk_x0.q.val());
        self.hi_a.read_address.next = (bit_cast::<12, 4>(self.ra_z.val()) << 8)
            | (bit_cast::<12, 4>(self.ra_y.val()) << 4)
            | bit_cast::<12, 4>(self.lk_x1.q.val());
        self.lo_b.read_address.next = (bit_cast::<12, 4>(self.rb_z.val()) << 8)
            | (bit_cast::<12, 4>(self.rb_y.val()) << 4)
            | bit_cast::<12, 4>(self.lk_x0.q.val());
        self.hi_b.read_address.next = (bit_cast::<12, 4>(self.rb_z.val()) << 8)
            | (bit_cast::<12, 4>(self.rb_y.val()) << 4)
            | bit_cast::<12, 4>(self.lk_x1.q.val());
        // A slot is looked up while the range queue has room for it (the read slot counts).
        if self.rd_valid.q.val() {
            self.lookup.next = self.lk_have.q.val() && (self.rq_n.q.val() < 3);
        } else {
            self.lookup.next = self.lk_have.q.val() && (self.rq_n.q.val() < 4);
        }
        self.lk_next.next = 4.into();
        if self.lk_mask[3].q.val() && (self.lk_slot.q.val() < 3) {
            self.lk_next.next = 3.into();
        }
        if self.lk_mask[2].q.val() && (self.lk_slot.q.val() < 2) {
            self.lk_next.next = 2.into();
        }
        if self.lk_mask[1].q.val() && (self.lk_slot.q.val() < 1) {
            self.lk_next.next = 1.into();
        }
        self.rd_valid.d.next = self.lookup.val();
        self.rd_in_a.d.next = self.ra_in.val();
        self.rd_in_b.d.next = self.rb_in.val();
        self.rd_last.d.next = self.lk_slot.q.val() == 4;
        self.rd_slast.d.next = self.lk_last.q.val();
        self.rd_q.d.next = self.lk_q.q.val();
        self.lk_free.next = !self.lk_have.q.val() || (self.lookup.val() && (self.lk_slot.q.val() == 4));
        self.pq_pop.next = self.lk_free.val() && (self.pq_n.q.val() != 0);
        if self.lookup.val() && (self.lk_slot.q.val() != 4) {
            self.lk_slot.d.next = self.lk_next.val();
        }
        if self.lk_free.val() {
            self.lk_have.d.next = self.pq_n.q.val() != 0;
        }
        if self.pq_pop.val() {
            self.lk_q.d.next = self.pq_head.val();
            self.lk_last.d.next = self.pq_head_l.val();
            self.lk_slot.d.next = self.h_first.val();
            self.lk_x0.d.next = 0.into();
            if self.hu[0].val() >= 25 {
                self.lk_x0.d.next = self.hu[0].val().get_bits::<4>(0) - 9;
            }
            self.lk_x1.d.next = 15.into();
            if self.hu[0].val() <= 38 {
                self.lk_x1.d.next = self.hu[0].val().get_bits::<4>(0) - 7;
            }
            self.lk_y[0].d.next = self.hu[1].val().get_bits::<4>(0) + 7;
            self.lk_y[1].d.next = self.hu[1].val().get_bits::<4>(0) + 8;
            self.lk_y[2].d.next = self.hu[1].val().get_bits::<4>(0) + 9;
            self.lk_z[0].d.next = self.hu[2].val().get_bits::<4>(0) + 7;
            self.lk_z[1].d.next = self.hu[2].val().get_bits::<4>(0) + 8;
            self.lk_z[2].d.next = self.hu[2].val().get_bits::<4>(0) + 9;
            for k in 0..3 {
                self.lk_vy[k].d.next = self.h_vy[k].val();
                self.lk_vz[k].d.next = self.h_vz[k].val();
            }
            for j in 0..4 {
                self.lk_mask[j].d.next = self.h_mask[j].val();
            }
        }
        // Point queue: push the transformed point, pop into the lookup stage.
        if self.transform.t2_valid.val() {
            for j in 0..4 {
                if self.pq_wr.q.val() == self.qid[j].val() {
                    self.pq_x[j].d.next = self.transform.result.val();
                    self.pq_l[j].d.next = self.l2.q.val();
                }
            }
            self.pq_wr.d.next = self.pq_wr.q.val() + 1;
        }
        if self.pq_pop.val() {
            self.pq_rd.d.next = self.pq_rd.q.val() + 1;
        }
        if self.transform.t2_valid.val() && !self.pq_pop.val() {
            self.pq_n.d.next = self.pq_n.q.val() + 1;
        } else if !self.transform.t2_valid.val() && self.pq_pop.val() {
            self.pq_n.d.next = self.pq_n.q.val() - 1;
        }
        // The read slot joins the range queue: its rows in place, each flagged if non-empty
        // (neither: a marker, queued only for a point's last slot).
        self.ra_ok.next = self.rd_in_a.q.val() && (self.lo_a.read_data.val() < self.hi_a.read_data.val());
        self.rb_ok.next = self.rd_in_b.q.val() && (self.lo_b.read_data.val() < self.hi_b.read_data.val());
        self.push.next = self.rd_valid.q.val() && (self.ra_ok.val() || self.rb_ok.val() || self.rd_last.q.val());
        // A point's last slot (the centre row alone) is split: its row B is row A from
        // `lo + P` on (a 14-bit sum, no wrap), if that is below `hi`; both sides stride `2P`.
        self.split_lo.next = bit_cast::<14, 13>(self.lo_a.read_data.val()) + self.pc14.val();
        self.split_ok.next = self.ra_ok.val() && (self.split_lo.val() < bit_cast::<14, 13>(self.hi_a.read_data.val()));
        if self.push.val() {
            for j in 0..4 {
                if self.rq_wr.q.val() == self.qid[j].val() {
                    self.rq_alo[j].d.next = self.lo_a.read_data.val();
                    self.rq_ahi[j].d.next = self.hi_a.read_data.val();
                    self.rq_av[j].d.next = self.ra_ok.val();
                    if self.rd_last.q.val() {
                        self.rq_blo[j].d.next = self.split_lo.val().get_bits::<13>(0);
                        self.rq_bhi[j].d.next = self.hi_a.read_data.val();
                        self.rq_bv[j].d.next = self.split_ok.val();
                    } else {
                        self.rq_blo[j].d.next = self.lo_b.read_data.val();
                        self.rq_bhi[j].d.next = self.hi_b.read_data.val();
                        self.rq_bv[j].d.next = self.rb_ok.val();
                    }
                    self.rq_last[j].d.next = self.rd_last.q.val();
                    self.rq_slast[j].d.next = self.rd_slast.q.val();
                    self.rq_q[j].d.next = self.rd_q.q.val();
                }
            }
            self.rq_wr.d.next = self.rq_wr.q.val() + 1;
        }
        // Issue: one chunk of each range a clock, range A (`is_addr .. is_end`) through the A
        // lanes and range B (`is_baddr .. is_bend`) through the B lanes, each side stepping
        // by the stride (`P`, or `2P` in a point's last slot, the split centre row); a side
        // stops with its last chunk, the entry is done when both have (a marker at once), and
        // its last chunk pair takes the next entry.
        self.stride13.next = self.pc13.val();
        self.stride14.next = self.pc14.val();
        if self.is_last.q.val() {
            self.stride13.next = self.pc13x2.val();
            self.stride14.next = self.pc14x2.val();
        }
        self.span.next = bit_cast::<14, 13>(self.is_end.q.val()) - bit_cast::<14, 13>(self.is_addr.q.val());
        self.span_b.next = bit_cast::<14, 13>(self.is_bend.q.val()) - bit_cast::<14, 13>(self.is_baddr.q.val());
        for b in 0..P {
            self.lanes[b].issue.next = self.is_have.q.val() && self.is_av.q.val();
            self.lanes[b].addr.next = self.is_addr.q.val();
            self.lanes[b].span.next = self.span.val();
            self.lanes[b].q.next = self.c0_q.q.val();
            self.lanes_b[b].issue.next = self.is_have.q.val() && self.is_bv.q.val();
            self.lanes_b[b].addr.next = self.is_baddr.q.val();
            self.lanes_b[b].span.next = self.span_b.val();
            self.lanes_b[b].q.next = self.c0_q.q.val();
        }
        self.fin_a.next = self.span.val() <= self.stride14.val();
        self.fin_b.next = self.span_b.val() <= self.stride14.val();
        self.done.next = self.is_have.q.val()
            && (!self.is_av.q.val() || self.fin_a.val())
            && (!self.is_bv.q.val() || self.fin_b.val());
        self.ch_last.next = self.done.val() && self.is_last.q.val();
        if self.is_have.q.val() {
            if self.is_av.q.val() {
                if self.fin_a.val() {
                    self.is_av.d.next = false;
                } else {
                    self.is_addr.d.next = self.is_addr.q.val() + self.stride13.val();
                }
            }
            if self.is_bv.q.val() {
                if self.fin_b.val() {
                    self.is_bv.d.next = false;
                } else {
                    self.is_baddr.d.next = self.is_baddr.q.val() + self.stride13.val();
                }
            }
        }
        self.c0_valid.d.next = self.is_have.q.val();
        self.c0_last.d.next = self.ch_last.val();
        self.c0_slast.d.next = self.is_slast.q.val();
        self.c0_q.d.next = self.is_q.q.val();
        self.rq_pop.next = (!self.is_have.q.val() || self.done.val()) && (self.rq_n.q.val() != 0);
        if !self.is_have.q.val() || self.done.val() {
            self.is_have.d.next = self.rq_n.q.val() != 0;
        }
        if self.rq_pop.val() {
            for j in 0..4 {
                if self.rq_rd.q.val() == self.qid[j].val() {
                    self.is_addr.d.next = self.rq_alo[j].q.val();
                    self.is_end.d.next = self.rq_ahi[j].q.val();
                    self.is_av.d.next = self.rq_av[j].q.val();
                    self.is_baddr.d.next = self.rq_blo[j].q.val();
                    self.is_bend.d.next = self.rq_bhi[j].q.val();
                    self.is_bv.d.next = self.rq_bv[j].q.val();
                    self.is_last.d.next = self.rq_last[j].q.val();
                    self.is_slast.d.next = self.rq_slast[j].q.val();
                    self.is_q.d.next = self.rq_q[j].q.val();
                }
            }
            self.rq_rd.d.next = self.rq_rd.q.val() + 1;
        }
        if self.push.val() && !self.rq_pop.val() {
            self.rq_n.d.next = self.rq_n.q.val() + 1;
        } else if !self.push.val() && self.rq_pop.val() {
            self.rq_n.d.next = self.rq_n.q.val() - 1;
        }
        // Control beside the lanes (s1..s4, keys) and the tree (levels 1..5).
        self.ctl_v[0].d.next = self.c0_valid.q.val();
        self.ctl_l[0].d.next = self.c0_last.q.val();
        self.ctl_s[0].d.next = self.c0_slast.q.val();
        self.ctl_q[0].d.next = self.c0_q.q.val();
        for k in 1..10 {
            self.ctl_v[k].d.next = self.ctl_v[k - 1].q.val();
            self.ctl_l[k].d.next = self.ctl_l[k - 1].q.val();
            self.ctl_s[k].d.next = self.ctl_s[k - 1].q.val();
            self.ctl_q[k].d.next = self.ctl_q[k - 1].q.val();
        }
        // The min-tree over the A lanes' keys (padded to 16 leaves with the neutral key).
        for j in 0..(P / 2) {
            if self.lanes[2 * j + 1].key.val() < self.lanes[2 * j].key.val() {
                self.t1[j].d.next = self.lanes[2 * j + 1].key.val();
            } else {
                self.t1[j].d.next = self.lanes[2 * j].key.val();
            }
        }
        for j in (P / 2)..8 {
            self.t1[j].d.next = self.cap_key.val();
        }
        for j in 0..4 {
            if self.t1[2 * j + 1].q.val() < self.t1[2 * j].q.val() {
                self.t2[j].d.next = self.t1[2 * j + 1].q.val();
            } else {
                self.t2[j].d.next = self.t1[2 * j].q.val();
            }
        }
        for j in 0..2 {
            if self.t2[2 * j + 1].q.val() < self.t2[2 * j].q.val() {
                self.t3[j].d.next = self.t2[2 * j + 1].q.val();
            } else {
                self.t3[j].d.next = self.t2[2 * j].q.val();
            }
        }
        if self.t3[1].q.val() < self.t3[0].q.val() {
            self.t4.d.next = self.t3[1].q.val();
        } else {
            self.t4.d.next = self.t3[0].q.val();
        }
        // The B lanes' tree, the same.
        for j in 0..(P / 2) {
            if self.lanes_b[2 * j + 1].key.val() < self.lanes_b[2 * j].key.val() {
                self.u1[j].d.next = self.lanes_b[2 * j + 1].key.val();
            } else {
                self.u1[j].d.next = self.lanes_b[2 * j].key.val();
            }
        }
        for j in (P / 2)..8 {
            self.u1[j].d.next = self.cap_key.val();
        }
        for j in 0..4 {
            if self.u1[2 * j + 1].q.val() < self.u1[2 * j].q.val() {
                self.u2[j].d.next = self.u1[2 * j + 1].q.val();
            } else {
                self.u2[j].d.next = self.u1[2 * j].q.val();
            }
        }
        for j in 0..2 {
            if self.u2[2 * j + 1].q.val() < self.u2[2 * j].q.val() {
                self.u3[j].d.next = self.u2[2 * j + 1].q.val();
            } else {
                self.u3[j].d.next = self.u2[2 * j].q.val();
            }
        }
        if self.u3[1].q.val() < self.u3[0].q.val() {
            self.u4.d.next = self.u3[1].q.val();
        } else {
            self.u4.d.next = self.u3[0].q.val();
        }
        // The smaller side.
        if self.u4.q.val() < self.t4.q.val() {
            self.t5.d.next = self.u4.q.val();
        } else {
            self.t5.d.next = self.t4.q.val();
        }
        // Accumulate a point's chunks; its last presents the result.
        self.m.next = self.t5.q.val();
        if self.acc_used.q.val() && (self.acc.q.val() < self.t5.q.val()) {
            self.m.next = self.acc.q.val();
        }
        self.nn_d.next = bit_cast::<34, 21>(self.m.val().get_bits::<21>(12));
        self.nn_valid_r.d.next = false;
        self.cost_valid_r.d.next = false;
        if self.ctl_v[9].q.val() {
            if self.ctl_l[9].q.val() {
                self.nn_valid_r.d.next = true;
                self.nn_index_r.d.next = self.m.val().get_bits::<12>(0);
                self.nn_dist_r.d.next = self.nn_d.val();
                self.nn_point_r.d.next = self.ctl_q[9].q.val();
                self.acc_used.d.next = false;
                self.fin.d.next = self.ctl_s[9].q.val();
            } else {
                self.acc.d.next = self.m.val();
                self.acc_used.d.next = true;
            }
        }
        // The cost adds each result the edge after it is presented (off the accumulator's
        // compare path); the particle's end presents the sum with the last result.
        self.cost_sum.next = self.cost_acc.q.val() + bit_cast::<48, 34>(self.nn_dist_r.q.val());
        if self.nn_valid_r.q.val() {
            self.cost_acc.d.next = self.cost_sum.val();
        }
        // State: idle or running a particle.
        if !self.run.q.val() {
            if self.start.val() {
                self.run.d.next = true;
                self.cost_acc.d.next = 0.into();
                self.last_taken.d.next = false;
            }
        } else {
            if self.take.val() {
                self.last_taken.d.next = self.scan_last.val();
            }
            if self.fin.q.val() {
                self.cost_valid_r.d.next = true;
                self.cost_r.d.next = self.cost_sum.val();
                self.fin.d.next = false;
                self.run.d.next = false;
            }
        }
        self.nn_valid.next = self.nn_valid_r.q.val();
        self.nn_index.next = self.nn_index_r.q.val();
        self.nn_dist.next = self.nn_dist_r.q.val();
        self.nn_point.next = self.nn_point_r.q.val();
        self.cost_valid.next = self.cost_valid_r.q.val();
        self.cost.next = self.cost_r.q.val();
    }
}
