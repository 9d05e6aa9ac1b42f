#include "soak_command.h"

#include <cstdio>
#include <string>
#include <string_view>

#include "command_line.h"
#include "rubble/error.h"
#include "soak.h"

namespace rubble::apps {

const char* const kSoakUsage =
    "usage: rubble soak [--bodies N] [--churn K] [--steps S] [--window W] [--threads T]\n"
    "\n"
    "  Rain onto a 200 m terrain mesh: N bodies (default 100000) of which K (default 1000) are removed, oldest\n"
    "  first, and as many created above every step, for S steps (default 20000). Every W steps (default 1000) it\n"
    "  prints the median and worst step time, the process's resident memory, the bodies and those frozen so far,\n"
    "  and at the end how memory and step time moved from the second window to the last. Exits 1 if a body froze.\n";

namespace {

[[noreturn]] void soakUsageError(const std::string& message) {
    std::fprintf(stderr, "rubble soak: %s\n\n%s", message.c_str(), kSoakUsage);
    std::exit(2);
}

}  // namespace

int runSoakCommand(int argc, char** argv) {
    soak::SoakSettings settings;
    for (int i = 2; i < argc; ++i) {
        const std::string_view a = argv[i];
        if (a == "--help" || a == "-h") {
            std::fputs(kSoakUsage, stdout);
            return 0;
        }
        if (i + 1 >= argc) soakUsageError(std::string(a) + " needs a value");
        const char* text = argv[++i];
        const auto number = [&](long lo, long hi) {
            const std::optional<long> v = parseWhole(text, lo, hi);
            if (!v) soakUsageError(wholeNumberError(a, text, lo, hi));
            return *v;
        };
        if (a == "--bodies")
            settings.bodies = static_cast<std::uint32_t>(number(1, 10'000'000));
        else if (a == "--churn")
            settings.churn = static_cast<std::uint32_t>(number(0, 10'000'000));
        else if (a == "--steps")
            settings.steps = number(1, 100'000'000);
        else if (a == "--window")
            settings.window = number(1, 100'000'000);
        else if (a == "--threads")
            settings.threads = static_cast<int>(number(0, 1024));
        else
            soakUsageError("unknown option '" + std::string(a) + "'");
    }
    if (settings.churn > settings.bodies) soakUsageError("--churn must not exceed --bodies");
    try {
        std::printf("soak       %u bodies, %u removed and created every step, %ld steps, threads %d\n\n",
                    settings.bodies, settings.churn, settings.steps, settings.threads);
        std::printf("%10s %12s %12s %12s %10s %8s\n", "step", "median ms", "worst ms", "resident MB", "bodies",
                    "frozen");
        const std::vector<soak::SoakWindow> windows = soak::runSoak(settings, [](const soak::SoakWindow& w) {
            std::printf("%10ld %12.3f %12.3f %12.1f %10u %8u\n", w.endStep, w.medianStepMs, w.worstStepMs, w.residentMb,
                        w.bodies, w.frozen);
            std::fflush(stdout);
        });
        // The first window holds the world's growth to its working size; compare from the second.
        if (windows.size() >= 3) {
            const soak::SoakWindow& first = windows[1];
            const soak::SoakWindow& last = windows.back();
            std::printf("\nfrom step %ld to %ld: resident memory %+.1f MB (%+.1f%%), median step %+.3f ms (%+.1f%%)\n",
                        first.endStep, last.endStep, last.residentMb - first.residentMb,
                        100.0 * (last.residentMb - first.residentMb) / first.residentMb,
                        last.medianStepMs - first.medianStepMs,
                        100.0 * (last.medianStepMs - first.medianStepMs) / first.medianStepMs);
        }
        return windows.back().frozen > 0 ? 1 : 0;
    } catch (const Error& e) {
        std::fprintf(stderr, "rubble: %s\n", e.what());
        return 1;
    }
}

}  // namespace rubble::apps
