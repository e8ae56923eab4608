// The plain Verilator driver every timing-free bench shares (no cocotb, no --timing): the bench
// top `RASTERHW_TOP` (a -D from sim/engines/runner.py build_plain_verilator) has an input `clk` and an
// output `done`; this main toggles `clk` until `done` (or +maxcyc= rising edges), then
// RASTERHW_TAIL more edges (for state the bench stores after `done`), times the loop with
// std::chrono and prints one JSON line:
//   {"sim_cycles": rising edges before done, "done", "run_s"[, "cycles"][, "lines"][, "errors"][, "status"]}
// where "cycles" / "lines" / "errors" / "status" (up to 64 bits) are the top's outputs of those names
// when the build defines RASTERHW_CYCLES / RASTERHW_LINES / RASTERHW_ERRORS / RASTERHW_STATUS. `final` blocks (the benches' dumps) run at the end.
// Separate clocks (a build defining RASTERHW_CLOCKS=N; sim/engines/verilator.py): the top has an
// N-bit input `clocks` instead of `clk`; bit k is clock k, with half period H and first rising edge
// at time F from +clock_k=H,F (default 1,0: every clock the same). The main steps from one clock
// event to the next, toggles every clock due at that time together and evaluates once (edges at
// the same time see each other's values from before them); "sim_cycles", +maxcyc= and the trace
// window count rising edges of clock 0, and the trace has one time step per time unit.
// A build with --trace-fst or --trace (waves on request: sim/engines/waves.py) writes the run's trace to
// the file named by +waves=PATH, two time steps per clock (rising edges at odd steps); with
// +trace_start=N / +trace_end=M only edges N .. M-1 (counted from 0, the tail included): the trace
// is opened at edge N (every value, then changes) and closed at edge M.
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#define RASTERHW_STR(x) #x
#define RASTERHW_XSTR(x) RASTERHW_STR(x)
#include RASTERHW_XSTR(RASTERHW_TOP.h)
#include "verilated.h"
#if VM_TRACE_FST
#include "verilated_fst_c.h"
using RasterhwTrace = VerilatedFstC;
#elif VM_TRACE_VCD
#include "verilated_vcd_c.h"
using RasterhwTrace = VerilatedVcdC;
#endif

#ifndef RASTERHW_TAIL
#define RASTERHW_TAIL 0
#endif

int main(int argc, char** argv) {
    const auto ctx = std::make_unique<VerilatedContext>();
    ctx->commandArgs(argc, argv);
    uint64_t maxcyc = 4000000000ull;
    const char* waves = nullptr;
    uint64_t tstart = 0, tend = UINT64_MAX;  // trace window: edges tstart .. tend-1
    for (int i = 1; i < argc; ++i) {
        if (!std::strncmp(argv[i], "+maxcyc=", 8)) maxcyc = std::strtoull(argv[i] + 8, nullptr, 10);
        if (!std::strncmp(argv[i], "+waves=", 7)) waves = argv[i] + 7;
        if (!std::strncmp(argv[i], "+trace_start=", 13)) tstart = std::strtoull(argv[i] + 13, nullptr, 10);
        if (!std::strncmp(argv[i], "+trace_end=", 11)) tend = std::strtoull(argv[i] + 11, nullptr, 10);
    }
#if VM_TRACE
    std::unique_ptr<RasterhwTrace> tfp;
    if (waves) ctx->traceEverOn(true);
#endif
    const auto top = std::make_unique<RASTERHW_TOP>(ctx.get());
#ifndef RASTERHW_CLOCKS
    top->clk = 0;
#endif
    top->eval();  // initial blocks: plusargs, $readmemh
#if VM_TRACE
    bool traced = false;  // the window has been opened (and perhaps closed)
    const auto window = [&](uint64_t k) {  // open the trace at edge tstart, close it at edge tend
        if (waves && !traced && k >= tstart && k < tend) {
            tfp = std::make_unique<RasterhwTrace>();
            top->trace(tfp.get(), 99);
            tfp->open(waves);
            if (k == 0) tfp->dump(0);
            traced = true;
        } else if (tfp && k >= tend) {
            tfp->close();
            tfp.reset();
        }
    };
    window(0);
#define RASTERHW_DUMP(t) \
    if (tfp) tfp->dump(t)
#else
    const auto window = [](uint64_t) {};
    if (waves) {
        std::fprintf(stderr, "+waves given, but this model was built without tracing\n");
        return 3;
    }
#define RASTERHW_DUMP(t)
#endif
    uint64_t n = 0, steps = 0;
#ifdef RASTERHW_CLOCKS
    constexpr int NCLK = RASTERHW_CLOCKS;
    uint64_t half[NCLK], next[NCLK];
    for (int k = 0; k < NCLK; ++k) {
        half[k] = 1;
        next[k] = 0;  // the time of the clock's next toggle (its first rising edge first)
        char key[32];
        std::snprintf(key, sizeof key, "+clock_%d=", k);
        const size_t len = std::strlen(key);
        for (int i = 1; i < argc; ++i) {
            if (std::strncmp(argv[i], key, len)) continue;
            char* end = nullptr;
            half[k] = std::strtoull(argv[i] + len, &end, 10);
            if (end && *end == ',') next[k] = std::strtoull(end + 1, nullptr, 10);
        }
        if (half[k] == 0) {
            std::fprintf(stderr, "+clock_%d: the half period must be at least 1\n", k);
            return 3;
        }
    }
    uint64_t level = 0;  // bit k: clock k's value
    top->clocks = 0;
    top->eval();
    const auto edge = [&]() {  // the next clock event: every clock due toggles, one eval
        uint64_t t = next[0];
        for (int k = 1; k < NCLK; ++k) t = next[k] < t ? next[k] : t;
        bool rise0 = false;
        for (int k = 0; k < NCLK; ++k) {
            if (next[k] != t) continue;
            level ^= 1ull << k;
            if (k == 0 && (level & 1)) rise0 = true;
            next[k] += half[k];
        }
        if (rise0) window(n);  // the edge about to happen
        top->clocks = level;
        top->eval();
        steps = t + 1;
        RASTERHW_DUMP(steps);
        return rise0;
    };
    const auto t0 = std::chrono::steady_clock::now();
    while (!top->done && n < maxcyc && !ctx->gotFinish()) {
        if (edge()) ++n;
    }
    const auto t1 = std::chrono::steady_clock::now();
    for (uint64_t k = 0; k < RASTERHW_TAIL;) {
        if (edge()) ++k;
    }
#else
    const auto edge = [&]() {
        window(steps / 2);  // the edge about to happen
        top->clk = 1;
        top->eval();
        ++steps;
        RASTERHW_DUMP(steps);
        top->clk = 0;
        top->eval();
        ++steps;
        RASTERHW_DUMP(steps);
    };
    const auto t0 = std::chrono::steady_clock::now();
    while (!top->done && n < maxcyc && !ctx->gotFinish()) {
        edge();
        ++n;
    }
    const auto t1 = std::chrono::steady_clock::now();
    for (int k = 0; k < RASTERHW_TAIL; ++k) edge();
#endif
    const double s = std::chrono::duration<double>(t1 - t0).count();
    const unsigned done = top->done;
    top->final();
#if VM_TRACE
    if (tfp) tfp->close();
#endif
    std::printf("{\"sim_cycles\": %llu, \"done\": %u, \"run_s\": %.9f", (unsigned long long)n, done, s);
#ifdef RASTERHW_CYCLES
    std::printf(", \"cycles\": %u", (unsigned)top->cycles);
#endif
#ifdef RASTERHW_LINES
    std::printf(", \"lines\": %u", (unsigned)top->lines);
#endif
#ifdef RASTERHW_ERRORS
    std::printf(", \"errors\": %u", (unsigned)top->errors);
#endif
#ifdef RASTERHW_STATUS
    std::printf(", \"status\": %llu", (unsigned long long)top->status);
#endif
    std::printf("}\n");
    return done ? 0 : 2;
}
