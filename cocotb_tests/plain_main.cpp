// The plain Verilator driver every timing-free bench shares (no cocotb, no --timing): the bench
// top `RASTERHW_TOP` (a -D from sim/runner.py build_plain_verilator) has an input `clk` and an
// output `done`; this main toggles `clk` until `done` (or +maxcyc= rising edges), then
// RASTERHW_TAIL more edges (for state the bench stores after `done`), times the loop with
// std::chrono and prints one JSON line:
//   {"sim_cycles": rising edges before done, "done", "run_s"[, "cycles"][, "lines"]}
// where "cycles" / "lines" are the top's outputs of those names when the build defines
// RASTERHW_CYCLES / RASTERHW_LINES. `final` blocks (the benches' dumps) run at the end.
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

#ifndef RASTERHW_TAIL
#define RASTERHW_TAIL 0
#endif

int main(int argc, char** argv) {
    const auto ctx = std::make_unique<VerilatedContext>();
    ctx->commandArgs(argc, argv);
    uint64_t maxcyc = 4000000000ull;
    for (int i = 1; i < argc; ++i)
        if (!std::strncmp(argv[i], "+maxcyc=", 8)) maxcyc = std::strtoull(argv[i] + 8, nullptr, 10);
    const auto top = std::make_unique<RASTERHW_TOP>(ctx.get());
    top->clk = 0;
    top->eval();  // initial blocks: plusargs, $readmemh
    uint64_t n = 0;
    const auto t0 = std::chrono::steady_clock::now();
    while (!top->done && n < maxcyc && !ctx->gotFinish()) {
        top->clk = 1;
        top->eval();
        top->clk = 0;
        top->eval();
        ++n;
    }
    const auto t1 = std::chrono::steady_clock::now();
    for (int k = 0; k < RASTERHW_TAIL; ++k) {
        top->clk = 1;
        top->eval();
        top->clk = 0;
        top->eval();
    }
    const double s = std::chrono::duration<double>(t1 - t0).count();
    const unsigned done = top->done;
    top->final();
    std::printf("{\"sim_cycles\": %llu, \"done\": %u, \"run_s\": %.9f", (unsigned long long)n, done, s);
#ifdef RASTERHW_CYCLES
    std::printf(", \"cycles\": %u", (unsigned)top->cycles);
#endif
#ifdef RASTERHW_LINES
    std::printf(", \"lines\": %u", (unsigned)top->lines);
#endif
    std::printf("}\n");
    return done ? 0 : 2;
}
