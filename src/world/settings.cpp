// Names of settings values, shared by scene files, the runner and the profile.
#include "rubble/settings.h"

#include <array>
#include <utility>

namespace rubble {
namespace {

constexpr std::array<std::pair<Effect, std::string_view>, kEffectCount> kEffectNames{{
    {Effect::Gravity, "gravity"},
    {Effect::Rotation, "rotation"},
    {Effect::Friction, "friction"},
    {Effect::Restitution, "restitution"},
    {Effect::Joints, "joints"},
    {Effect::Sleeping, "sleeping"},
    {Effect::ContinuousCollision, "continuous_collision"},
}};

constexpr std::array<std::pair<Integrator, std::string_view>, 4> kIntegratorNames{{
    {Integrator::SemiImplicitEuler, "semi_implicit_euler"},
    {Integrator::ExplicitEuler, "explicit_euler"},
    {Integrator::Verlet, "verlet"},
    {Integrator::RungeKutta4, "rk4"},
}};

constexpr std::array<std::pair<BroadPhaseKind, std::string_view>, 3> kBroadPhaseNames{{
    {BroadPhaseKind::Auto, "auto"},
    {BroadPhaseKind::SweepAndPrune, "sap"},
    {BroadPhaseKind::Grid, "grid"},
}};

constexpr std::array<std::pair<PositionCorrection, std::string_view>, 3> kPositionCorrectionNames{{
    {PositionCorrection::SoftStep, "soft_step"},
    {PositionCorrection::Baumgarte, "baumgarte"},
    {PositionCorrection::SplitImpulse, "split_impulse"},
}};

template <class E, std::size_t N>
std::string_view nameOf(const std::array<std::pair<E, std::string_view>, N>& table, E value) {
    for (const auto& [e, name] : table)
        if (e == value) return name;
    return "?";
}

template <class E, std::size_t N>
std::optional<E> valueOf(const std::array<std::pair<E, std::string_view>, N>& table, std::string_view name) {
    for (const auto& [e, n] : table)
        if (n == name) return e;
    return std::nullopt;
}

}  // namespace

std::string_view effectName(Effect e) { return nameOf(kEffectNames, e); }
std::optional<Effect> effectFromName(std::string_view name) { return valueOf(kEffectNames, name); }
std::string_view integratorName(Integrator i) { return nameOf(kIntegratorNames, i); }
std::optional<Integrator> integratorFromName(std::string_view name) { return valueOf(kIntegratorNames, name); }
std::string_view broadPhaseName(BroadPhaseKind b) { return nameOf(kBroadPhaseNames, b); }
std::optional<BroadPhaseKind> broadPhaseFromName(std::string_view name) { return valueOf(kBroadPhaseNames, name); }

std::string_view positionCorrectionName(PositionCorrection p) { return nameOf(kPositionCorrectionNames, p); }
std::optional<PositionCorrection> positionCorrectionFromName(std::string_view name) {
    return valueOf(kPositionCorrectionNames, name);
}

}  // namespace rubble
