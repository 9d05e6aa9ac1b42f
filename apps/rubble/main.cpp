// rubble: the command-line runner. Loads a scene, steps it and prints what each stage cost.

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <optional>
#include <random>
#include <string>
#include <string_view>
#include <thread>
#include <vector>

#include "accuracy_command.h"
#include "command_line.h"
#include "rubble/build_info.h"
#include "rubble/error.h"
#include "rubble/limits.h"
#include "rubble/runtime.h"
#include "rubble/scene.h"
#include "rubble/world.h"
#include "soak_command.h"
#include "trace_writer.h"

namespace {

constexpr const char* kUsage =
    "usage: rubble run [SCENE] [--steps N] [--threads T] [--broadphase auto|sap|grid] [--profile] [--trace FILE]\n"
    "                  [--hash] [--realtime SECONDS [--rate HZ]] [--set KEY=VALUE]...\n"
    "\n"
    "  SCENE         scene file (JSON); default: the standard scene S1, scenes/s1_pyramid.json\n"
    "  --steps N     number of steps (default: the scene's own)\n"
    "  --threads T   worker threads (default: the scene's setting; 0 = all cores)\n"
    "  --broadphase  moving-pair algorithm: auto (picked from the scene), sap or grid (default: the scene's)\n"
    "  --profile     print the per-stage table (median ms per step, share of the step, worst step, mean)\n"
    "  --trace FILE  write a Chrome trace-event JSON file (open it in Perfetto or chrome://tracing)\n"
    "  --hash        print a hash of the final state of all bodies\n"
    "  --realtime S  run the scene for S seconds of wall time through the Runtime (physics on its own thread at a\n"
    "                fixed rate, this thread rendering at 60 Hz by interpolation) and print the physics rate, the\n"
    "                dropped steps and the profile sampled from the rendered frames\n"
    "  --rate HZ     the Runtime's physics rate for --realtime (default 120)\n"
    "  --set K=V     override the scene's setting K (a key of the scene format's settings, docs/scene_format.md) with\n"
    "                V, a JSON value or a bare name: --set substeps=4 --set position_correction=soft_step\n";

struct Options {
    std::string scene;
    long steps = -1;
    int threads = -1;
    std::optional<rubble::BroadPhaseKind> broadPhase;
    bool profile = false;
    bool hash = false;
    std::string trace;
    double realtime = 0;
    double rate = 120;
    std::vector<std::string> settings;  ///< --set overrides, KEY=VALUE, in order
};

[[noreturn]] void usageError(const std::string& message) {
    std::fprintf(stderr, "rubble: %s\n\n%s", message.c_str(), kUsage);
    std::exit(2);
}

long parseCount(std::string_view flag, const char* text, long min, long max) {
    const std::optional<long> value = rubble::apps::parseWhole(text, min, max);
    if (!value) usageError(rubble::apps::wholeNumberError(flag, text, min, max));
    return *value;
}

/// KEY=VALUE as a JSON object {"KEY": VALUE}; VALUE is taken as JSON if it starts like a number, an array, an object
/// or a string in quotes, or is true or false, and as a bare name (quoted here) otherwise.
std::string settingObject(std::string_view text) {
    const std::size_t eq = text.find('=');
    if (eq == std::string_view::npos || eq == 0) usageError("--set takes KEY=VALUE, not '" + std::string(text) + "'");
    const std::string_view key = text.substr(0, eq), value = text.substr(eq + 1);
    const bool json = !value.empty() &&
                      (value.front() == '"' || value.front() == '[' || value.front() == '{' || value.front() == '-' ||
                       (value.front() >= '0' && value.front() <= '9') || value == "true" || value == "false");
    std::string out;
    const auto appendQuoted = [&out](std::string_view s) {
        out.push_back('"');
        for (const char c : s) {
            if (c == '"' || c == '\\') out.push_back('\\');
            out.push_back(c);
        }
        out.push_back('"');
    };
    out.push_back('{');
    appendQuoted(key);
    out.append(": ");
    if (json)
        out.append(value);
    else
        appendQuoted(value);
    out.push_back('}');
    return out;
}

std::string defaultScene() { return rubble::apps::defaultScene(RUBBLE_SCENES_DIR); }

Options parseOptions(int argc, char** argv) {
    if (argc < 2) usageError("missing command");
    const std::string_view command = argv[1];
    if (command == "--help" || command == "-h" || command == "help") {
        std::fputs(kUsage, stdout);
        std::fputs("\n", stdout);
        std::fputs(rubble::apps::kAccuracyUsage, stdout);
        std::fputs("\n", stdout);
        std::fputs(rubble::apps::kSoakUsage, stdout);
        std::exit(0);
    }
    if (command != "run") usageError("unknown command '" + std::string(command) + "' (commands: run, accuracy, soak)");
    Options o;
    for (int i = 2; i < argc; ++i) {
        const std::string_view a = argv[i];
        auto value = [&]() -> const char* {
            if (i + 1 >= argc) usageError(std::string(a) + " needs a value");
            return argv[++i];
        };
        if (a == "--steps")
            o.steps = parseCount(a, value(), 0, rubble::limits::kMaxRunnerSteps);
        else if (a == "--threads")
            o.threads = static_cast<int>(parseCount(a, value(), 0, 1024));
        else if (a == "--broadphase") {
            const char* name = value();
            o.broadPhase = rubble::broadPhaseFromName(name);
            if (!o.broadPhase) usageError(std::string("--broadphase takes auto, sap or grid, not '") + name + "'");
        } else if (a == "--profile")
            o.profile = true;
        else if (a == "--hash")
            o.hash = true;
        else if (a == "--trace")
            o.trace = value();
        else if (a == "--realtime")
            o.realtime = static_cast<double>(parseCount(a, value(), 1, 3600));
        else if (a == "--rate")
            o.rate = static_cast<double>(parseCount(a, value(), 1, 100000));
        else if (a == "--set")
            o.settings.emplace_back(value());
        else if (a == "--help" || a == "-h") {
            std::fputs(kUsage, stdout);
            std::exit(0);
        } else if (const auto error = rubble::apps::takeSceneArgument(a, o.scene)) {
            usageError(*error);
        }
    }
    if (o.scene.empty()) o.scene = defaultScene();
    return o;
}

double median(std::vector<double> v) {
    if (v.empty()) return 0;
    const std::size_t mid = v.size() / 2;
    std::nth_element(v.begin(), v.begin() + mid, v.end());
    if (v.size() % 2) return v[mid];
    return 0.5 * (v[mid] + *std::max_element(v.begin(), v.begin() + mid));
}

/// Times of the steps (or of one stage) of a run: every one up to a million, then a uniform random sample of a
/// million (reservoir sampling), so that a run of any length keeps bounded memory; the largest is kept exactly.
class TimingSamples {
public:
    void add(double ms) {
        ++count_;
        total_ += ms;
        largest_ = std::max(largest_, ms);
        if (samples_.size() < kKept) {
            samples_.push_back(ms);
            return;
        }
        const std::uint64_t slot = random_() % count_;
        if (slot < kKept) samples_[slot] = ms;
    }
    std::uint64_t count() const { return count_; }
    bool empty() const { return count_ == 0; }
    double median() const { return ::median(samples_); }
    double largest() const { return largest_; }
    double mean() const { return count_ == 0 ? 0.0 : total_ / static_cast<double>(count_); }

private:
    static constexpr std::size_t kKept = std::size_t{1} << 20;
    std::vector<double> samples_;
    std::uint64_t count_ = 0;
    double total_ = 0;
    double largest_ = 0;
    std::mt19937_64 random_{1};
};

/// A one-line progress bar on stderr, only when stderr is a terminal.
class ProgressBar {
public:
    explicit ProgressBar(long total) : total_(total), enabled_(isatty(STDERR_FILENO) && total >= 50) {}
    void update(long done) {
        if (!enabled_) return;
        const int width = 40;
        const int filled = static_cast<int>(width * done / total_);
        if (filled == last_ && done != total_) return;
        last_ = filled;
        std::fprintf(stderr, "\r[%.*s%*s] %ld/%ld steps", filled, "########################################",
                     width - filled, "", done, total_);
        if (done == total_) std::fputs("\r\033[K", stderr);
        std::fflush(stderr);
    }

private:
    long total_;
    bool enabled_;
    int last_ = -1;
};

std::string effectList(rubble::EffectSet set) {
    std::string out;
    for (int b = 0; b < rubble::kEffectCount; ++b) {
        const auto e = static_cast<rubble::Effect>(1u << b);
        if (!set.has(e)) continue;
        if (!out.empty()) out += ", ";
        out += rubble::effectName(e);
    }
    return out.empty() ? "none" : out;
}

void printStageTable(const std::vector<TimingSamples>& stageMs, const TimingSamples& stepMs) {
    const double stepMedian = stepMs.median();
    // The worst step shows hitches (a static tree built inside a step, a burst of contacts) that a median hides; the
    // mean is what peers' benchmarks report (Box3D's prints a run's total time).
    std::printf("\n%-22s %8s %12s %8s %12s %12s\n", "stage", "ran", "median ms", "share", "worst ms", "mean ms");
    for (int k = 0; k < rubble::kStageCount; ++k) {
        const auto stage = static_cast<rubble::Stage>(k);
        // Continuous collision and events are choices a scene makes: a scene without them has no row to show a zero in.
        if ((stage == rubble::Stage::Ccd || stage == rubble::Stage::Events) && stageMs[k].empty()) continue;
        const double m = stageMs[k].median();
        std::printf("%-22s %8llu %12.4f %7.1f%% %12.4f %12.4f\n", std::string(rubble::stageName(stage)).c_str(),
                    static_cast<unsigned long long>(stageMs[k].count()), m,
                    stepMedian > 0 ? 100.0 * m / stepMedian : 0.0, stageMs[k].largest(), stageMs[k].mean());
    }
    std::printf("%-22s %8llu %12.4f %7.1f%% %12.4f %12.4f\n", "step", static_cast<unsigned long long>(stepMs.count()),
                stepMedian, 100.0, stepMs.largest(), stepMs.mean());
}

/// --realtime: the scene through the Runtime, with this thread standing in for a 60 Hz render loop.
int runRealtime(const Options& options, rubble::World world) {
    rubble::RuntimeSettings settings;
    settings.rate = options.rate;
    rubble::Runtime runtime(std::move(world), settings);
    std::vector<TimingSamples> stageMs(rubble::kStageCount);
    TimingSamples stepMs;
    std::vector<double> interpolateMs;
    std::uint64_t lastStep = 0;
    using Clock = std::chrono::steady_clock;
    const auto frame = std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(1.0 / 60.0));
    runtime.start();
    const auto begin = Clock::now();
    const auto end =
        begin + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(options.realtime));
    for (auto next = begin + frame; Clock::now() < end; next += frame) {
        const auto t0 = Clock::now();
        const rubble::RenderFrame& f = runtime.interpolate();
        interpolateMs.push_back(std::chrono::duration<double, std::milli>(Clock::now() - t0).count());
        if (f.step != lastStep && f.slotCount() > 0) {  // sample the profile of the newest step once
            lastStep = f.step;
            stepMs.add(f.profile.stepMs);
            for (int k = 0; k < rubble::kStageCount; ++k)
                if (f.profile.stages[k].ran) stageMs[k].add(f.profile.stages[k].ms);
        }
        std::this_thread::sleep_until(next);
    }
    runtime.stop();
    const double wall = std::chrono::duration<double>(Clock::now() - begin).count();
    const rubble::RuntimeStats stats = runtime.stats();
    std::printf("\nrealtime   %.2f s wall, physics at %.6g Hz (step %.6g s), at most %d steps per wake-up\n", wall,
                settings.rate, 1.0 / settings.rate, settings.maxStepsPerWake);
    std::printf("physics    %llu steps = %.1f Hz (%.1f Hz in the last window), simulated/wall %.3f\n",
                static_cast<unsigned long long>(stats.steps), static_cast<double>(stats.steps) / wall, stats.physicsHz,
                stats.slowdown);
    std::printf("dropped    %llu steps (%.3f s), most steps in one wake-up %u%s\n",
                static_cast<unsigned long long>(stats.droppedSteps), stats.droppedSeconds, stats.maxStepsPerWake,
                stats.behind ? ", behind at the end" : "");
    std::printf("render     %zu frames, interpolate median %.4f ms\n", interpolateMs.size(), median(interpolateMs));
    std::printf("\nprofile    sampled from %llu steps shown by the frames:",
                static_cast<unsigned long long>(stepMs.count()));
    printStageTable(stageMs, stepMs);
    if (options.hash)
        std::printf("\nstate hash %016llx (depends on the machine's timing)\n",
                    static_cast<unsigned long long>(runtime.world().stateHash()));
    return 0;
}

int run(const Options& options) {
    rubble::Scene scene = rubble::loadScene(options.scene);
    for (const std::string& setting : options.settings)
        rubble::overrideSettings(scene, settingObject(setting), "--set " + setting);
    if (options.threads >= 0) scene.settings.threads = options.threads;
    if (options.broadPhase) scene.settings.broadPhase = *options.broadPhase;
    const long steps = options.steps >= 0 ? options.steps : scene.steps;

    rubble::World world(scene.settings);
    const std::vector<rubble::BodyId> ids = rubble::instantiate(scene, world);

    rubble::SceneFigureMeter figures(scene, world, ids);
    const auto dynamicCount = static_cast<std::size_t>(std::count_if(
        ids.begin(), ids.end(), [&](rubble::BodyId id) { return world.bodyType(id) == rubble::BodyType::Dynamic; }));

    const rubble::BuildInfo build = rubble::buildInfo();
    std::printf("scene      %s (%s)\n", scene.name.c_str(), options.scene.c_str());
    std::printf("bodies     %u (%zu dynamic)\n", world.bodyCount(), dynamicCount);
    std::printf("steps      %ld of %.6g s, %d substep(s), integrator %s\n", steps, scene.settings.timeStep,
                scene.settings.substeps, std::string(rubble::integratorName(scene.settings.integrator)).c_str());
    const rubble::SolverSettings& solver = scene.settings.solver;
    std::printf("solver     %s, %d+%d iterations, warm starting %s, resting-load guess %s, shock propagation %s\n",
                std::string(rubble::positionCorrectionName(solver.positionCorrection)).c_str(),
                scene.settings.velocityIterations, scene.settings.positionIterations,
                solver.warmStarting ? "on" : "off", solver.warmStarting && solver.seedRestingLoads ? "on" : "off",
                solver.shockPropagation ? "on" : "off");
    std::printf("threads    %d%s, SIMD %s (%d float lanes, core built for %s)\n", scene.settings.threads,
                scene.settings.threads == 0 ? " (all cores)" : "", build.instructionSet, build.floatLanes,
                build.coreBuild);
    std::printf("broad      %s (setting)\n", std::string(rubble::broadPhaseName(scene.settings.broadPhase)).c_str());
    std::printf("effects    declared: %s\n           simulated: %s\n", effectList(scene.settings.effects).c_str(),
                effectList(world.activeEffects()).c_str());
    if (options.realtime > 0) return runRealtime(options, std::move(world));

    std::vector<TimingSamples> stageMs(rubble::kStageCount);
    TimingSamples stepMs;
    std::optional<TraceWriter> trace;
    if (!options.trace.empty()) trace.emplace(options.trace);  // an unwritable path fails before the run
    ProgressBar progress(steps);
    std::uint32_t frozen = 0;
    long droppedSteps = 0;
    std::uint64_t events = 0;
    for (long s = 0; s < steps; ++s) {
        world.step(scene.settings.timeStep);
        figures.record(world);
        const rubble::Profile& p = world.lastProfile();
        stepMs.add(p.stepMs);
        events += p.events;
        for (int k = 0; k < rubble::kStageCount; ++k)
            if (p.stages[k].ran) stageMs[k].add(p.stages[k].ms);
        if (trace) trace->addStep(p);
        if (p.droppedPairs > 0 && droppedSteps++ < 10)
            std::fprintf(stderr,
                         "warning: step %ld: %llu candidate pairs past the pair budget were dropped (%u kept): bodies "
                         "are piled onto one another far past what contact can hold (docs/limits.md)\n",
                         s, static_cast<unsigned long long>(p.droppedPairs), p.movingPairs);
        if (p.droppedStaticHits > 0 && droppedSteps++ < 10)
            std::fprintf(stderr,
                         "warning: step %ld: %llu static candidates past the static budget were dropped: static bodies "
                         "or mesh triangles are piled far past what contact can hold (docs/limits.md)\n",
                         s, static_cast<unsigned long long>(p.droppedStaticHits));
        for (rubble::BodyId id : world.takeFrozenBodies()) {
            if (frozen++ < 10)
                std::fprintf(
                    stderr,
                    "warning: body %u froze at step %ld: its state became non-finite or left the coordinate limit\n",
                    id.index, s);
        }
        progress.update(s + 1);
    }
    if (frozen > 10) std::fprintf(stderr, "warning: %u bodies froze in all\n", frozen);
    if (droppedSteps > 10) std::fprintf(stderr, "warning: %ld steps dropped pairs past the budget\n", droppedSteps);

    const double stepMedian = stepMs.median();
    if (options.profile) {
        printStageTable(stageMs, stepMs);
        const rubble::Profile& last = world.lastProfile();
        std::printf("\ncounts     bodies %u, moving %u (last step)\n", world.bodyCount(), last.movingCount);
        std::printf("broad      %s; pairs: %u moving-moving, %u moving-static, %u moving-mesh (%u triangles)\n",
                    last.broadPhase == rubble::BroadPhaseKind::Auto
                        ? "did not run"
                        : std::string(rubble::broadPhaseName(last.broadPhase)).c_str(),
                    last.movingPairs, last.staticPairs, last.meshPairs, last.meshTriangles);
        std::printf("narrow     %u manifolds, %u contact points; %u manifolds reused (pairs moved < %g mm)\n",
                    last.manifolds, last.contactPoints, last.reusedManifolds,
                    1000.0 * scene.settings.manifoldReuseDistance);
        std::printf(
            "cache      %u of %u manifolds continue last step's, %u of %u points warm-started; %u new ones started "
            "from resting loads\n",
            last.matchedManifolds, last.manifolds, last.warmStartedPoints, last.contactPoints, last.seededManifolds);
        std::printf("islands    %u islands, the largest of %u bodies; %u bodies asleep\n", last.islands,
                    last.largestIsland, last.sleepingBodies);
        std::printf(
            "solver     %u constraints: %u in %u blocks of small islands, %u in large islands; at most %u "
            "colours, SIMD lanes %.0f%% filled; %s, %d+%d iterations\n",
            last.constraints, last.constraints - last.largeIslandConstraints, last.solverBlocks,
            last.largeIslandConstraints, last.colors, 100.0 * last.laneOccupancy,
            std::string(rubble::positionCorrectionName(scene.settings.solver.positionCorrection)).c_str(),
            scene.settings.velocityIterations, scene.settings.positionIterations);
        if (last.joints > 0)
            std::printf(
                "joints     %u joints, %.3f ms of the last step; large islands' joints: %u colours across the threads, "
                "%u ball joints in SIMD lanes\n",
                last.joints, last.jointMs, last.jointColours, last.batchedJoints);
    } else {
        std::printf("\nstep       median %.4f ms over %llu steps (mean %.4f ms)\n", stepMedian,
                    static_cast<unsigned long long>(stepMs.count()), stepMs.mean());
    }

    if (!stageMs[static_cast<int>(rubble::Stage::Events)].empty())
        std::printf("events     %llu contact and sensor events over the run; %u sensor pairs in the last step\n",
                    static_cast<unsigned long long>(events), world.lastProfile().sensorPairs);
    std::printf("\n");
    for (const rubble::SceneFigureMeter::Result& figure : figures.results(world))
        std::printf("figure     %s\n", figure.text.c_str());
    if (options.hash) std::printf("state hash %016llx\n", static_cast<unsigned long long>(world.stateHash()));
    if (trace) {
        trace->finish();
        std::printf("trace      %s (%zu events)\n", options.trace.c_str(), trace->eventCount());
    }
    return 0;
}

}  // namespace

int main(int argc, char** argv) {
    if (argc >= 2 && std::string_view(argv[1]) == "accuracy") return rubble::apps::runAccuracyCommand(argc, argv);
    if (argc >= 2 && std::string_view(argv[1]) == "soak") return rubble::apps::runSoakCommand(argc, argv);
    const Options options = parseOptions(argc, argv);
    try {
        return run(options);
    } catch (const rubble::Error& e) {
        std::fprintf(stderr, "rubble: %s\n", e.what());
        return 1;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "rubble: unexpected error: %s\n", e.what());
        return 1;
    }
}
