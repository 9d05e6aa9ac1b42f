#include "accuracy_command.h"

#include <sys/stat.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <ctime>
#include <fstream>
#include <map>
#include <string>
#include <string_view>
#include <vector>

#include "command_line.h"
#include "measurement.h"
#include "report.h"
#include "rubble/build_info.h"
#include "rubble/error.h"
#include "sweeps.h"

namespace rubble::apps {

const char* const kAccuracyUsage =
    "usage: rubble accuracy [--quick] [--out DIR] [--threads T] [--only ID[,ID]...]\n"
    "\n"
    "  Runs the measurement scenes across each knob and writes DIR/ACCURACY.md, DIR/accuracy/accuracy.csv and one\n"
    "  plot per scene, DIR/accuracy/ID.svg (gnuplot). `rubble accuracy --out docs` makes docs/ACCURACY.md.\n"
    "\n"
    "  --quick       each knob's default and extremes only, shorter runs (about a minute; what CI runs)\n"
    "  --out DIR     where to write (default: accuracy-report)\n"
    "  --threads T   worker threads of every run (default 1: the steadiest times; the threads knob adds 2)\n"
    "  --only IDS    only these scenes (comma-separated ids, as in the CSV's scene column)\n";

namespace {

using namespace rubble::accuracy;

struct AccuracyOptions {
    bool quick = false;
    std::string out = "accuracy-report";
    int threads = 1;
    std::vector<std::string> only;
};

[[noreturn]] void accuracyUsageError(const std::string& message) {
    std::fprintf(stderr, "rubble accuracy: %s\n\n%s", message.c_str(), kAccuracyUsage);
    std::exit(2);
}

AccuracyOptions parse(int argc, char** argv) {
    AccuracyOptions o;
    for (int i = 2; i < argc; ++i) {
        const std::string_view a = argv[i];
        auto value = [&]() -> const char* {
            if (i + 1 >= argc) accuracyUsageError(std::string(a) + " needs a value");
            return argv[++i];
        };
        if (a == "--quick") {
            o.quick = true;
        } else if (a == "--out") {
            o.out = value();
            if (o.out.empty()) accuracyUsageError("--out needs a directory");
        } else if (a == "--threads") {
            const char* text = value();
            const std::optional<long> n = parseWhole(text, 1, 1024);
            if (!n) accuracyUsageError(wholeNumberError(a, text, 1, 1024));
            o.threads = static_cast<int>(*n);
        } else if (a == "--only") {
            std::string list = value();
            for (std::size_t start = 0; start <= list.size();) {
                const std::size_t comma = std::min(list.find(',', start), list.size());
                if (comma > start) o.only.push_back(list.substr(start, comma - start));
                start = comma + 1;
            }
        } else if (a == "--help" || a == "-h") {
            std::fputs(kAccuracyUsage, stdout);
            std::exit(0);
        } else {
            accuracyUsageError("unknown option '" + std::string(a) + "'");
        }
    }
    return o;
}

/// Creates `path` and its parents as needed; throws naming the one that could not be made.
void makeDirectories(const std::string& path) {
    for (std::size_t slash = path.find('/', 1);; slash = path.find('/', slash + 1)) {
        const std::string prefix = path.substr(0, slash);
        struct stat info {};
        if (stat(prefix.c_str(), &info) == 0) {
            if (!S_ISDIR(info.st_mode)) throw Error("accuracy: '" + prefix + "' is not a directory");
        } else if (mkdir(prefix.c_str(), 0755) != 0) {
            throw Error("accuracy: cannot create the directory '" + prefix + "'");
        }
        if (slash == std::string::npos) return;
    }
}

/// First line of a command's output, or empty.
std::string commandOutput(const std::string& command) {
    std::string out;
    if (FILE* pipe = popen(command.c_str(), "r")) {
        char line[256];
        if (std::fgets(line, sizeof line, pipe)) out = line;
        pclose(pipe);
    }
    while (!out.empty() && (out.back() == '\n' || out.back() == '\r')) out.pop_back();
    return out;
}

std::string machineDescription() {
    std::string model = "unknown CPU";
    std::ifstream cpuinfo("/proc/cpuinfo");
    for (std::string line; std::getline(cpuinfo, line);)
        if (line.rfind("model name", 0) == 0 && line.find(':') != std::string::npos) {
            model = line.substr(line.find(':') + 2);
            break;
        }
    return model + ", " + std::to_string(sysconf(_SC_NPROCESSORS_ONLN)) + " hardware threads";
}

std::string buildDescription() {
    const BuildInfo b = buildInfo();
    std::string commit = commandOutput("git -C '" RUBBLE_SOURCE_DIR "' rev-parse --short HEAD 2>/dev/null");
    if (!commit.empty() &&
        !commandOutput("git -C '" RUBBLE_SOURCE_DIR "' status --porcelain --untracked-files=no 2>/dev/null").empty())
        commit += " with local changes";
    return std::string("Rubble ") + (commit.empty() ? "(commit unknown)" : commit) + ", core built for " + b.coreBuild +
           " (" + b.instructionSet + ", " + std::to_string(b.floatLanes) + " float lanes), " + "g++ " __VERSION__;
}

std::string today() {
    const std::time_t now = std::time(nullptr);
    char text[32];
    std::strftime(text, sizeof text, "%Y-%m-%d %H:%M UTC", std::gmtime(&now));
    return text;
}

std::string scenesDirectory() {
    if (access("scenes/hard", R_OK) == 0) return "scenes";
    return RUBBLE_SCENES_DIR;
}

}  // namespace

int runAccuracyCommand(int argc, char** argv) {
    const AccuracyOptions options = parse(argc, argv);
    using Clock = std::chrono::steady_clock;
    const auto begin = Clock::now();
    const Length length = options.quick ? Length::Quick : Length::Full;
    try {
        if (std::system("gnuplot --version > /dev/null 2>&1") != 0)
            throw Error(
                "accuracy: gnuplot is needed for the plots and was not found (scripts/install-deps.sh installs "
                "gnuplot-nox)");
        std::vector<MeasurementScene> scenes = measurementScenes(scenesDirectory());
        for (const std::string& id : options.only)
            if (std::none_of(scenes.begin(), scenes.end(), [&](const MeasurementScene& s) { return s.id == id; })) {
                std::string known;
                for (const MeasurementScene& s : scenes) known += (known.empty() ? "" : ", ") + s.id;
                throw Error("accuracy: --only names no scene '" + id + "' (scenes: " + known + ")");
            }
        const std::string plotDir = options.out + "/accuracy";
        makeDirectories(plotDir);

        WorldSettings defaults;
        defaults.threads = options.threads;
        std::vector<SceneResults> results;
        for (MeasurementScene& scene : scenes) {
            if (!options.only.empty() &&
                std::find(options.only.begin(), options.only.end(), scene.id) == options.only.end())
                continue;
            const auto sceneBegin = Clock::now();
            SceneResults sceneResults;
            std::map<std::string, std::size_t> measured;  // settings key -> run that measured them
            for (PlannedRun& run : planRuns(scene, defaults, length)) {
                RunResult result{std::move(run), {}, {}};
                const std::string key = settingsKey(result.run.settings);
                if (const auto it = measured.find(key); it != measured.end()) {
                    result.measured = sceneResults.runs[it->second].measured;
                    result.failure = sceneResults.runs[it->second].failure;
                } else {
                    try {
                        result.measured = scene.measure(result.run.settings, length);
                    } catch (const Error& e) {
                        result.failure = e.what();
                    }
                    measured.emplace(key, sceneResults.runs.size());
                }
                sceneResults.runs.push_back(std::move(result));
            }
            sceneResults.seconds = std::chrono::duration<double>(Clock::now() - sceneBegin).count();
            const RunResult& d = sceneResults.runs.front();
            std::printf("%-24s %3zu runs (%3zu measured) in %6.1f s; defaults: %s %.4g %s, %.4f ms/step\n",
                        scene.id.c_str(), sceneResults.runs.size(), measured.size(), sceneResults.seconds,
                        scene.errorName.c_str(), d.measured.error, scene.unit.c_str(), d.measured.msPerStep);
            std::fflush(stdout);
            sceneResults.scene = std::move(scene);
            results.push_back(std::move(sceneResults));
        }
        const auto effectsBegin = Clock::now();
        const EffectCosts effects = measureEffectCosts(options.threads, length);
        std::printf("%-24s %3d runs                in %6.1f s; all effects %.4f ms/step\n", "effects", kEffectCount + 1,
                    std::chrono::duration<double>(Clock::now() - effectsBegin).count(), effects.all.msPerStep);

        writeCsv(plotDir + "/accuracy.csv", results);
        writePlots(plotDir, results);
        ReportContext context;
        context.command = "rubble accuracy" + std::string(options.quick ? " --quick" : "") + " --threads " +
                          std::to_string(options.threads);
        context.machine = machineDescription();
        context.build = buildDescription();
        context.date = today();
        context.length = length;
        context.seconds = std::chrono::duration<double>(Clock::now() - begin).count();
        writeMarkdown(options.out + "/ACCURACY.md", "accuracy", results, effects, context);
        std::printf("\nwrote %s/ACCURACY.md, %s/accuracy.csv and %zu plots in %.0f s\n", options.out.c_str(),
                    plotDir.c_str(), results.size(), context.seconds);
        // Every setting a sweep hands out is one the engine accepts: a run that failed is a fault of the report or
        // of the engine, and the exit code says so (the report shows which).
        std::size_t failed = 0;
        for (const SceneResults& scene : results)
            for (const RunResult& r : scene.runs) failed += r.failure.empty() ? 0 : 1;
        if (failed > 0) {
            std::fprintf(stderr, "rubble accuracy: %zu runs failed (see the report)\n", failed);
            return 3;
        }
        return 0;
    } catch (const Error& e) {
        std::fprintf(stderr, "rubble: %s\n", e.what());
        return 1;
    }
}

}  // namespace rubble::apps
