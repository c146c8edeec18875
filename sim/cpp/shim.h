// The C entry points of one Verilated model, templated on its class (Vpipe16, Vboard, ...).
// sim/build.rs writes, per model, a few lines that instantiate these for the class and copy
// the ports between the packed u64 words and the model's fields (the only part that depends
// on the port list); everything else lives here once.
//
// Time: clock low, eval, dump at t - 5; clock high (the rising edge), eval, dump at t.
#pragma once
#include <cstdint>
#include "verilated.h"
#include "verilated_vcd_c.h"

namespace pficp {

template <class Top>
struct Handle {
    VerilatedContext* ctx;
    Top* top;
    VerilatedVcdC* tfp;
};

template <class Top>
void* make() {
    Handle<Top>* h = new Handle<Top>;
    h->ctx = new VerilatedContext;
    h->ctx->traceEverOn(true);
    h->ctx->randReset(0);
    h->top = new Top(h->ctx, "top");
    h->tfp = nullptr;
    h->top->clock = 0;
    h->top->eval();
    return h;
}

template <class Top>
void destroy(void* p) {
    Handle<Top>* h = static_cast<Handle<Top>*>(p);
    h->top->final();
    if (h->tfp) {
        h->tfp->close();
        delete h->tfp;
    }
    delete h->top;
    delete h->ctx;
    delete h;
}

template <class Top>
void tick(void* p, uint64_t t) {
    Handle<Top>* h = static_cast<Handle<Top>*>(p);
    h->top->clock = 0;
    h->ctx->time(t - 5);
    h->top->eval();
    if (h->tfp) h->tfp->dump(t - 5);
    h->top->clock = 1;
    h->ctx->time(t);
    h->top->eval();
    if (h->tfp) h->tfp->dump(t);
}

// Opens a VCD and dumps the current state at time t. Returns 0 on success.
template <class Top>
int trace_open(void* p, const char* path, uint64_t t) {
    Handle<Top>* h = static_cast<Handle<Top>*>(p);
    if (h->tfp) {
        h->tfp->close();
        delete h->tfp;
    }
    h->tfp = new VerilatedVcdC;
    h->top->trace(h->tfp, 99);
    h->tfp->open(path);
    if (!h->tfp->isOpen()) {
        delete h->tfp;
        h->tfp = nullptr;
        return 1;
    }
    h->tfp->dump(t);
    return 0;
}

template <class Top>
void trace_flush(void* p) {
    Handle<Top>* h = static_cast<Handle<Top>*>(p);
    if (h->tfp) h->tfp->flush();
}

template <class Top>
void trace_close(void* p) {
    Handle<Top>* h = static_cast<Handle<Top>*>(p);
    if (h->tfp) {
        h->tfp->close();
        delete h->tfp;
        h->tfp = nullptr;
    }
}

template <class Top>
Top* top(void* p) {
    return static_cast<Handle<Top>*>(p)->top;
}

}  // namespace pficp

// The extern "C" entry points pficp_<name>_* of class `Top`; the model's port copies
// pficp_<name>_set_inputs / _get_outputs follow it in the generated file.
#define PFICP_SHIM(Top, name)                                                                 \
    extern "C" void* pficp_##name##_new() { return pficp::make<Top>(); }                      \
    extern "C" void pficp_##name##_free(void* p) { pficp::destroy<Top>(p); }                  \
    extern "C" void pficp_##name##_tick(void* p, uint64_t t) { pficp::tick<Top>(p, t); }      \
    extern "C" int pficp_##name##_trace_open(void* p, const char* path, uint64_t t) {         \
        return pficp::trace_open<Top>(p, path, t);                                            \
    }                                                                                         \
    extern "C" void pficp_##name##_trace_flush(void* p) { pficp::trace_flush<Top>(p); }       \
    extern "C" void pficp_##name##_trace_close(void* p) { pficp::trace_close<Top>(p); }
