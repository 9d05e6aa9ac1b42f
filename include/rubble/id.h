#pragma once
// Handles are small value types: a slot index plus a generation. A default-constructed handle is null.
// This header includes nothing else on purpose.

namespace rubble {

/// Handle to a body. Stays valid while the body exists, whatever else is added or removed.
struct BodyId {
    unsigned index = 0;       ///< slot in the world's slot map
    unsigned generation = 0;  ///< 0 means null; bumped each time the slot is reused

    constexpr bool isNull() const { return generation == 0; }
    friend constexpr bool operator==(BodyId a, BodyId b) { return a.index == b.index && a.generation == b.generation; }
    friend constexpr bool operator!=(BodyId a, BodyId b) { return !(a == b); }
};

/// Handle to a shape owned by a world. Shapes are shared by any number of bodies.
struct ShapeId {
    unsigned index = 0;
    unsigned generation = 0;  ///< 0 means null

    constexpr bool isNull() const { return generation == 0; }
    friend constexpr bool operator==(ShapeId a, ShapeId b) {
        return a.index == b.index && a.generation == b.generation;
    }
    friend constexpr bool operator!=(ShapeId a, ShapeId b) { return !(a == b); }
};

/// Handle to a joint. Stays valid until the joint is destroyed, or one of its bodies is (a broken joint keeps its
/// handle: see World::isJointBroken).
struct JointId {
    unsigned index = 0;
    unsigned generation = 0;  ///< 0 means null

    constexpr bool isNull() const { return generation == 0; }
    friend constexpr bool operator==(JointId a, JointId b) {
        return a.index == b.index && a.generation == b.generation;
    }
    friend constexpr bool operator!=(JointId a, JointId b) { return !(a == b); }
};

}  // namespace rubble
