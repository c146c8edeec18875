// Tiny test design for hdl-gen (hand-written, in the style of rust_hdl output: several
// modules in one file, `$` in module names, widths extended by context):
// a registered 18 x 18 signed multiplier (one DSP48A1), a 1024 x 48 synchronous RAM
// (block RAM), and a registered 12-bit adder widened with bit_cast-style masking (LUTs +
// CARRY4, the longest logic path).
module top(clock, a, b, we, waddr, raddr, x, y, p, rdata, sum);
    input wire clock;
    input wire signed [17:0] a;
    input wire signed [17:0] b;
    input wire we;
    input wire [9:0] waddr;
    input wire [9:0] raddr;
    input wire [11:0] x;
    input wire [11:0] y;
    output wire signed [35:0] p;
    output reg [47:0] rdata;
    output reg [12:0] sum;
    reg signed [17:0] a_r;
    reg signed [17:0] b_r;
    reg [47:0] mem [0:1023];
    top$mul mul(.clock(clock), .a(a_r), .b(b_r), .p(p));
    always @(posedge clock) begin
        a_r <= a;
        b_r <= b;
        if (we) mem[waddr] <= {p[35:24], p};
        rdata <= mem[raddr];
        sum <= ((x) & 13'h1fff) + ((y) & 13'h1fff);
    end
endmodule

module top$mul(clock, a, b, p);
    input wire clock;
    input wire signed [17:0] a;
    input wire signed [17:0] b;
    output reg signed [35:0] p;
    always @(posedge clock) p <= $signed(a) * $signed(b);
endmodule
