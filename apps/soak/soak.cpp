#include "soak.h"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <variant>

#include "rubble/scene.h"

namespace rubble::soak {
namespace {

constexpr float kTerrainHalf = 100.0f;

/// S3's rolling terrain (y = 2 sin(x / 8) cos(z / 8)) over 200 x 200 m in 1 m cells, from the scene format's terrain
/// generator.
TriangleMeshDef terrain() {
    const Scene scene = parseScene(R"({"shapes": {"terrain": {"type": "mesh", "grid": {"cells": [200, 200],
        "min": [-100, -100], "max": [100, 100], "amplitude": 2, "wavelength": 8}}}})",
                                   "the soak's terrain");
    return std::get<TriangleMeshDef>(scene.shapes.front());
}

double median(std::vector<double> v) {
    if (v.empty()) return 0;
    std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
    return v[v.size() / 2];
}

}  // namespace

double residentMegabytes() {
    std::FILE* f = std::fopen("/proc/self/statm", "r");
    if (!f) return 0;
    unsigned long size = 0, resident = 0;
    const int got = std::fscanf(f, "%lu %lu", &size, &resident);
    std::fclose(f);
    if (got != 2) return 0;
    return static_cast<double>(resident) * static_cast<double>(sysconf(_SC_PAGESIZE)) / (1024.0 * 1024.0);
}

Soak::Soak(const SoakSettings& settings)
    : settings_(settings), world_(WorldSettings{.threads = settings.threads}), random_(settings.seed) {
    BodyDef ground;
    ground.type = BodyType::Static;
    ground.shape = world_.createShape(terrain());
    world_.createBody(ground);
    ball_ = world_.createShape(SphereDef{0.3f});
    box_ = world_.createShape(BoxDef{{0.25f, 0.25f, 0.25f}});
    for (std::uint32_t i = 0; i < settings_.bodies; ++i) createBody();
}

void Soak::createBody() {
    std::uniform_real_distribution<float> across(-kTerrainHalf + 2, kTerrainHalf - 2), height(2.0f, 20.0f),
        unit(-1.0f, 1.0f);
    BodyDef def;
    def.shape = random_() % 2 ? ball_ : box_;
    def.position = {across(random_), height(random_), across(random_)};
    def.orientation = Quat::fromAxisAngle({unit(random_), unit(random_), unit(random_)}, 3.0f * unit(random_));
    def.linearVelocity = {unit(random_), -5.0f, unit(random_)};
    bodies_.push_back(world_.createBody(def));
}

void Soak::step() {
    const std::uint32_t churn = std::min<std::uint32_t>(settings_.churn, static_cast<std::uint32_t>(bodies_.size()));
    for (std::uint32_t i = 0; i < churn; ++i) {
        world_.destroyBody(bodies_.front());
        bodies_.pop_front();
    }
    for (std::uint32_t i = 0; i < churn; ++i) createBody();
    world_.step(1.0f / 60.0f);
    frozen_ += static_cast<std::uint32_t>(world_.takeFrozenBodies().size());
}

std::vector<SoakWindow> runSoak(const SoakSettings& settings, const std::function<void(const SoakWindow&)>& report) {
    Soak soak(settings);
    std::vector<SoakWindow> windows;
    std::vector<double> stepMs;
    for (long s = 1; s <= settings.steps; ++s) {
        soak.step();
        stepMs.push_back(soak.world().lastProfile().stepMs);
        if (s % settings.window == 0 || s == settings.steps) {
            SoakWindow w;
            w.endStep = s;
            w.worstStepMs = *std::max_element(stepMs.begin(), stepMs.end());
            w.medianStepMs = median(std::move(stepMs));
            stepMs.clear();
            w.residentMb = residentMegabytes();
            w.bodies = soak.world().bodyCount();
            w.frozen = soak.frozen();
            windows.push_back(w);
            report(w);
        }
    }
    return windows;
}

}  // namespace rubble::soak
