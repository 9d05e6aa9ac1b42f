#pragma once
// Handles are small value types: a slot index plus a generation. A default-constructed handle is null.
// Every kind of object a world owns has one, all of the same make; the kind only keeps them apart in the types.
// This header includes nothing else on purpose.

namespace rubble {

template <class Tag>
struct Handle {
    unsigned index = 0;       ///< slot in the world's slot map for this kind
    unsigned generation = 0;  ///< 0 means null; bumped each time the slot is reused

    constexpr bool isNull() const { return generation == 0; }
    friend constexpr bool operator==(Handle a, Handle b) { return a.index == b.index && a.generation == b.generation; }
    friend constexpr bool operator!=(Handle a, Handle b) { return !(a == b); }
};

struct BodyTag;
struct ShapeTag;
struct JointTag;
struct CharacterTag;

/// Handle to a body. Stays valid while the body exists, whatever else is added or removed.
using BodyId = Handle<BodyTag>;
/// Handle to a shape owned by a world. Shapes are shared by any number of bodies.
using ShapeId = Handle<ShapeTag>;
/// Handle to a joint. Stays valid until the joint is destroyed, or one of its bodies is (a broken joint keeps its
/// handle: see World::isJointBroken).
using JointId = Handle<JointTag>;
/// Handle to a character a Runtime steps (Runtime::addCharacter).
using CharacterId = Handle<CharacterTag>;

}  // namespace rubble
