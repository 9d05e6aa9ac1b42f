#pragma once
// The stage benchmarks that run on the world's pool measure it at 1 and 2 threads (the machines Rubble is measured
// on have two cores), in microseconds of wall time.
#include <benchmark/benchmark.h>

inline void atOneAndTwoThreads(benchmark::internal::Benchmark* b) {
    b->Arg(1)->Arg(2)->ArgName("threads")->Unit(benchmark::kMicrosecond)->UseRealTime();
}
