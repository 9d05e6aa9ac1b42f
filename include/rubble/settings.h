#pragma once
#include <cstdint>
#include <optional>
#include <string_view>

#include "rubble/math.h"

namespace rubble {

/// Physical effects a scene may call for. The step is assembled from the stages its effects need.
enum class Effect : std::uint32_t {
    Gravity = 1u << 0,
    Rotation = 1u << 1,
    Friction = 1u << 2,
    Restitution = 1u << 3,
    Joints = 1u << 4,
    Sleeping = 1u << 5,
    ContinuousCollision = 1u << 6,
};
inline constexpr int kEffectCount = 7;

/// A set of effects (bit set over Effect).
struct EffectSet {
    std::uint32_t bits = 0;

    constexpr bool has(Effect e) const { return (bits & static_cast<std::uint32_t>(e)) != 0; }
    constexpr EffectSet with(Effect e) const { return {bits | static_cast<std::uint32_t>(e)}; }
    constexpr EffectSet without(Effect e) const { return {bits & ~static_cast<std::uint32_t>(e)}; }
    friend constexpr bool operator==(EffectSet a, EffectSet b) { return a.bits == b.bits; }

    /// What a world simulates when the scene declares nothing: everything but continuous collision.
    static constexpr EffectSet defaults() { return {0x3Fu}; }
    static constexpr EffectSet all() { return {0x7Fu}; }
};

/// Name used in scene files and the profile ("gravity", "rotation", ...).
std::string_view effectName(Effect e);
/// Parses an effect name; empty if unknown.
std::optional<Effect> effectFromName(std::string_view name);

/// How motion is integrated over one step. Semi-implicit (symplectic) Euler is the default; the others exist
/// to measure what accuracy costs.
enum class Integrator : std::uint8_t { SemiImplicitEuler, ExplicitEuler, Verlet, RungeKutta4 };

std::string_view integratorName(Integrator i);
std::optional<Integrator> integratorFromName(std::string_view name);

/// How the contact solver removes overlap. The soft step (soft contact constraints whose stiffness follows the substep
/// rate, then relax iterations that take the push-out velocity away again) is the default: with four substeps of 2 + 1
/// iterations and 60 Hz contacts it is the one setting measured to hold every case of the hard-case suite that any
/// setting holds, built or dropped, with the resting-load guess on or off (docs/solver_defaults.md). Its contacts are
/// springs, so stacks settle under their weight by load / stiffness (S5's hundred rows: 21-25 cm). Baumgarte (a
/// fraction of the overlap beyond a slop fed back as approach speed inside the velocity iterations) at one substep
/// and 8 iterations keeps built stacks stiffer (S1 and S2 within 0.1 mm, S5 1.2 cm with the guess) and costs about a
/// quarter less, but drops a tower, a heavy box on a light one and S5 dropped or without the guess: the standard
/// scenes S1-S4 use it, as SCENES.md's 8 + 2 iterations call for. Split impulses correct positions with
/// pseudo-velocities that never reach the real ones, so that push-out adds no energy.
enum class PositionCorrection : std::uint8_t { SoftStep, Baumgarte, SplitImpulse };

std::string_view positionCorrectionName(PositionCorrection p);
std::optional<PositionCorrection> positionCorrectionFromName(std::string_view name);

/// Contact solver knobs beyond the iteration counts.
struct SolverSettings {
    PositionCorrection positionCorrection = PositionCorrection::SoftStep;
    /// Start each step from last step's impulses (matched by the contact cache).
    bool warmStarting = true;
    /// With warm starting: a contact new this step through which a body rests on something lower starts from the
    /// impulses that would hold that body still under gravity, with everything resting on it (computed top down,
    /// solver/resting_loads.h). Without it, a stack that appears at once gets its loads only as fast as the
    /// iterations pass them down, one layer or so each, and its upper layers fall into the layers below. Bodies still
    /// landing on their supports get no guess, and impulses that stopped an impact are not passed down as loads.
    bool seedRestingLoads = true;
    /// Approach speeds below this do not bounce, m/s: resting contacts would otherwise jitter.
    float restitutionThreshold = 1.0f;
    /// Soft step: stiffness of contacts as a natural frequency (capped at a quarter of the substep rate), Hz, and
    /// damping ratio. Contacts against static bodies use twice the frequency. 60 Hz is the cap at four substeps of
    /// 60 Hz steps; Box3D's 30 Hz (with one iteration and one relax a substep) lets a dropped tower fall, and contacts
    /// stiffer than the cap need more than two iterations to converge (S5 falls at 120 Hz).
    float contactHertz = 60.0f;
    float contactDampingRatio = 10.0f;
    /// Soft step: stiffness of rigid joints (distance, ball, hinge) as a natural frequency (capped at a quarter of
    /// the substep rate), Hz, and damping ratio. Baumgarte and split impulses correct joints by `baumgarte`.
    float jointHertz = 60.0f;
    float jointDampingRatio = 2.0f;
    /// Largest speed at which overlap is pushed apart (soft step and Baumgarte), m/s, per contact: a column of
    /// overlapping bodies adds up its contacts' speeds, so ten layers 25% into each other threw the top at 27 m/s at
    /// 3 m/s and send it up at 4.7 m/s at 0.5 (scenes/hard/overlap_recovery.json). A soft contact under load may push
    /// as fast as its spring needs to hold that load (a heavy slab on light cubes sinks through them otherwise).
    float maxPushOutVelocity = 0.5f;
    /// Baumgarte and split impulses: fraction of the overlap removed per step, and the overlap left alone, m.
    float baumgarte = 0.2f;
    float linearSlop = 0.005f;
    /// Shock propagation (Guendelman et al. 2003): after the velocity iterations, one more pass over the contacts
    /// from the ground up in which the lower body of each contact counts as immovable, so that every body ends the
    /// iterations supported by what is under it. Tall stacks stop sinking and rocking at a few iterations, for one
    /// serial pass over the contacts; what it costs is that loads no longer flow down within the pass. Baumgarte
    /// and split impulses only: the soft step's springs, held from below, would take their softness twice. Not for
    /// bodies resting on two or more others, as in a brick wall: what the iterations leave of their turning is held
    /// level by level and grows with every row (S5 with it: the top row ends 140 m up after 200 steps).
    bool shockPropagation = false;
};

/// When bodies fall asleep (only in scenes that declare Effect::Sleeping). A body rests while its speed is below
/// `linearThreshold`, its angular speed below `angularThreshold`, and its angular speed times its reach (the largest
/// distance of its shape from the centre of mass) below `linearThreshold` as well, so that a long body turning slowly
/// at its ends does not count as resting. An island whose bodies have all rested for `timeToSleep` falls asleep: its
/// bodies stop being integrated and its contacts stop being solved until something wakes it. The defaults are Box2D
/// v3's (0.05 m/s, 0.5 s); the angular threshold only matters for tiny bodies, whose reach makes the size-aware term
/// weak.
struct SleepSettings {
    float linearThreshold = 0.05f;  ///< m/s, >= 0
    float angularThreshold = 0.5f;  ///< rad/s, >= 0
    float timeToSleep = 0.5f;       ///< s, >= 0
};

enum class BroadPhaseKind : std::uint8_t { Auto, SweepAndPrune, Grid };

std::string_view broadPhaseName(BroadPhaseKind b);
std::optional<BroadPhaseKind> broadPhaseFromName(std::string_view name);

/// World-wide settings. Every knob that trades accuracy for time is here.
struct WorldSettings {
    Vec3 gravity{0, -9.81f, 0};
    float timeStep = 1.0f / 60.0f;  ///< the fixed step the runner uses (a Runtime steps at its own rate), s
    /// Collision runs once a step; integration and the solve run once a substep (docs/solver_defaults.md).
    int substeps = 4;
    /// Contact solver iterations per substep. Position iterations are the relax iterations of the soft step and
    /// the pseudo-velocity iterations of split impulses; Baumgarte has none.
    int velocityIterations = 2;
    int positionIterations = 1;
    SolverSettings solver;
    int threads = 0;  ///< size of the task arena; 0 = all hardware threads
    /// Bounding boxes are enlarged by this much on every side (besides the motion of the step), so that pairs are
    /// found before their bodies touch (speculative contacts), m.
    float contactMargin = 0.02f;
    /// A pair of bodies whose shapes have moved less than this relative to each other since its contacts were
    /// computed, and neither of which has turned more than 2 degrees, keeps those contacts (contact recycling, as
    /// Box3D does within 5 cm and Jolt's body pair cache within 1 mm and 2 degrees): their normal and where they hold
    /// each body stay as computed, and their depths follow the bodies. Besides saving the narrow phase's work, this is
    /// what lets tall stacks stand: soft contacts sag, and contacts computed again every step from the sagged stack
    /// turn its small lean into sideways pushes that lean it further (docs/solver_defaults.md). Pairs of spheres and
    /// capsules are computed every step (their kernels cost less than the lookup). 0 computes every pair every
    /// step, m.
    float manifoldReuseDistance = 0.02f;
    /// A pair of polytopes (hull-hull, box-hull) that touched last step makes its contact again from the feature
    /// that decided it (a reference face or an edge pair) without testing every axis, while that feature's
    /// separation stays within this distance of what the full search found; then the search runs again. The contact
    /// may then come from a feature the search would have left for another up to about this much shallower (Box3D
    /// keeps its SAT cache the same way, at its linear slop); 0 searches every pair every step, m.
    float contactFeatureDrift = 0.005f;
    Integrator integrator = Integrator::SemiImplicitEuler;
    /// Effects the scene declares. The engine removes those the content cannot show (see World::activeEffects).
    EffectSet effects = EffectSet::defaults();
    BroadPhaseKind broadPhase = BroadPhaseKind::Auto;
    SleepSettings sleep;
    /// Contacts that approach faster than this report a hit (ContactHitEvent), m/s, >= 0.
    float hitEventSpeed = 1.0f;
};

}  // namespace rubble
