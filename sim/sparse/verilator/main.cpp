// Plain Verilator driver for tb_sparse_vp.v: toggles `clk` until `done` (or +maxcyc= edges),
// times that loop and prints one JSON line {"sim_cycles", "cycles", "done", "run_s"}.
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include "Vtb_sparse_vp.h"
#include "verilated.h"

int main(int argc, char** argv) {
    const auto ctx = std::make_unique<VerilatedContext>();
    ctx->commandArgs(argc, argv);
    uint64_t maxcyc = 4000000000ull;
    for (int i = 1; i < argc; ++i)
        if (!std::strncmp(argv[i], "+maxcyc=", 8)) maxcyc = std::strtoull(argv[i] + 8, nullptr, 10);
    const auto top = std::make_unique<Vtb_sparse_vp>(ctx.get());
    top->clk = 0;
    top->eval();
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
    const double s = std::chrono::duration<double>(t1 - t0).count();
    const unsigned done = top->done;
    top->final();
    std::printf("{\"sim_cycles\": %llu, \"cycles\": %u, \"done\": %u, \"run_s\": %.9f}\n",
                (unsigned long long)n, (unsigned)top->cycles, done, s);
    return done ? 0 : 2;
}
