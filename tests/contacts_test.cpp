// Contact cache: manifolds and points are matched across steps by stable keys and feature ids, impulses carry over
// exactly, separated pairs are forgotten, and a body that reuses a slot inherits nothing. Points whose feature is
// new take the impulses of an unmatched old point within kContactMatchDistance.
#include <gtest/gtest.h>

#include <algorithm>

#include "contacts/contact_cache.h"
#include "core/parallel.h"

using namespace rubble;
using namespace rubble::detail;

namespace {

Manifold manifoldWith(std::initializer_list<std::uint32_t> features) {
    Manifold m;
    m.normal = {0, -1, 0};
    // Points one metre apart per feature id, so that only features match unless a test moves them.
    for (std::uint32_t f : features) m.points[m.pointCount++] = {{static_cast<float>(f), 0, 0}, 0.01f, f};
    return m;
}

struct Fixture {
    BodyStorage storage;
    TaskPool pool{2};
    std::vector<BodyId> ids;

    Fixture() {
        for (int i = 0; i < 6; ++i) {
            std::uint32_t dense;
            ids.push_back(storage.allocate(BodySet::Moving, dense));
        }
    }
    std::uint32_t dense(int body) const { return storage.find(ids[body])->dense; }
};

}  // namespace

TEST(ContactCache, CarriesImpulsesOfMatchingPointsAndForgetsTheRest) {
    Fixture f;
    ContactCache cache;
    Contacts step1;
    step1.pairs = {{f.dense(0), f.dense(1)}, {f.dense(2), f.dense(3)}};
    step1.manifolds = {manifoldWith({10, 11, 12, 13}), manifoldWith({7})};
    std::vector<PointImpulse> impulses;
    cache.warmStart(step1, f.storage, f.pool, impulses);
    EXPECT_EQ(cache.matchedManifolds(), 0u);  // nothing to match on the first step
    ASSERT_EQ(impulses.size(), 2u * kMaxManifoldPoints);
    for (int i = 0; i < 4; ++i) impulses[i] = {1.0f + i, 0.5f, -0.25f};  // what a solver would have accumulated
    impulses[kMaxManifoldPoints] = {9, 9, 9};
    cache.remember(step1, impulses, f.pool);

    // Step 2: the first pair keeps three of its features (one new, in another order); the second pair separated.
    Contacts step2;
    step2.pairs = {{f.dense(0), f.dense(1)}, {f.dense(4), f.dense(5)}};
    step2.manifolds = {manifoldWith({13, 99, 10, 11}), manifoldWith({7})};
    cache.warmStart(step2, f.storage, f.pool, impulses);
    EXPECT_EQ(cache.matchedManifolds(), 1u);
    EXPECT_EQ(cache.matchedPoints(), 3u);
    EXPECT_EQ(impulses[0].normal, 4.0f);  // feature 13 was the fourth point
    EXPECT_EQ(impulses[1].normal, 0.0f);  // feature 99 is new
    EXPECT_EQ(impulses[2].normal, 1.0f);
    EXPECT_EQ(impulses[3].normal, 2.0f);
    EXPECT_EQ(impulses[3].tangent2, -0.25f);
    EXPECT_EQ(impulses[kMaxManifoldPoints].normal, 0.0f) << "a different pair with the same feature id";
    ASSERT_EQ(cache.carried().size(), 2u);
    EXPECT_EQ(cache.carried()[0], 1u);
    EXPECT_EQ(cache.carried()[1], 0u) << "new pairs carry nothing (the resting-load guess starts them)";
    cache.remember(step2, impulses, f.pool);

    // Step 3: the pair (2, 3) comes back, but it was forgotten when it separated.
    Contacts step3;
    step3.pairs = {{f.dense(2), f.dense(3)}};
    step3.manifolds = {manifoldWith({7})};
    cache.warmStart(step3, f.storage, f.pool, impulses);
    EXPECT_EQ(cache.matchedManifolds(), 0u);
    ASSERT_EQ(cache.carried().size(), 1u);
    EXPECT_EQ(cache.carried()[0], 0u);
}

TEST(ContactCache, NewFeaturesTakeTheImpulsesOfAnOldPointNearby) {
    Fixture f;
    ContactCache cache;
    Contacts step1;
    step1.pairs = {{f.dense(0), f.dense(1)}};
    step1.manifolds = {manifoldWith({10, 11})};
    std::vector<PointImpulse> impulses;
    cache.warmStart(step1, f.storage, f.pool, impulses);
    impulses[0] = {5, 1, 2};
    impulses[1] = {6, 3, 4};
    cache.remember(step1, impulses, f.pool);

    // The kernel now names the corner at x = 11 differently (a reference-face flip), 1 cm from where it was, and a
    // third point appears 30 cm away from anything old.
    Contacts step2;
    step2.pairs = step1.pairs;
    step2.manifolds = {manifoldWith({10, 50, 51})};
    step2.manifolds[0].points[1].position = {11.01f, 0, 0};
    step2.manifolds[0].points[2].position = {10.3f, 0, 0};
    cache.warmStart(step2, f.storage, f.pool, impulses);
    EXPECT_EQ(cache.matchedPoints(), 2u);
    EXPECT_EQ(impulses[0].normal, 5.0f);  // by feature
    EXPECT_EQ(impulses[1].normal, 6.0f);  // by position
    EXPECT_EQ(impulses[1].tangent2, 4.0f);
    EXPECT_EQ(impulses[2].normal, 0.0f);  // too far from the only old point left
}

TEST(ContactCache, ABodyReusingASlotInheritsNothingAndRemovalsKeepOthersMatched) {
    Fixture f;
    ContactCache cache;
    Contacts before;
    before.pairs = {{f.dense(0), f.dense(1)}, {f.dense(4), f.dense(5)}};
    before.manifolds = {manifoldWith({1}), manifoldWith({2})};
    std::vector<PointImpulse> impulses;
    cache.warmStart(before, f.storage, f.pool, impulses);
    impulses[0].normal = impulses[kMaxManifoldPoints].normal = 5;
    cache.remember(before, impulses, f.pool);

    // Body 1 goes; a new body takes its slot (a new generation). Removal swaps the last body into body 1's row,
    // so bodies 4 and 5 may change dense index: their manifold must still match through their slots.
    f.storage.release(f.ids[1]);
    std::uint32_t dense;
    f.ids[1] = f.storage.allocate(BodySet::Moving, dense);
    Contacts after;
    after.pairs = {{f.dense(0), f.dense(1)}, {f.dense(4), f.dense(5)}};
    after.manifolds = {manifoldWith({1}), manifoldWith({2})};
    cache.warmStart(after, f.storage, f.pool, impulses);
    EXPECT_EQ(impulses[0].normal, 0.0f) << "the new body in the old slot must start cold";
    EXPECT_EQ(impulses[kMaxManifoldPoints].normal, 5.0f);
    EXPECT_EQ(cache.matchedManifolds(), 1u);
}

TEST(ContactCache, StaticSidesAndThreadCountsAgree) {
    // Many manifolds against a static body, matched on 1 and on 2 threads: the same impulses come back.
    auto run = [](int threads) {
        BodyStorage storage;
        std::uint32_t dense;
        storage.allocate(BodySet::Static, dense);
        for (int i = 0; i < 5000; ++i) storage.allocate(BodySet::Moving, dense);
        TaskPool pool(threads);
        Contacts contacts;
        for (std::uint32_t i = 0; i < 5000; ++i) {
            contacts.pairs.push_back({i, 0, false, true, i % 7});
            contacts.manifolds.push_back(manifoldWith({i % 3, 100 + i % 5}));
        }
        ContactCache cache;
        std::vector<PointImpulse> impulses;
        cache.warmStart(contacts, storage, pool, impulses);
        for (std::size_t k = 0; k < impulses.size(); ++k) impulses[k].normal = float(k);
        cache.remember(contacts, impulses, pool);
        cache.warmStart(contacts, storage, pool, impulses);
        EXPECT_EQ(cache.matchedPoints(), 10000u);
        return impulses;
    };
    const auto one = run(1), two = run(2);
    ASSERT_EQ(one.size(), two.size());
    for (std::size_t k = 0; k < one.size(); ++k) ASSERT_EQ(one[k].normal, two[k].normal);
    EXPECT_EQ(one[4 * 17 + 1].normal, float(4 * 17 + 1));
}

TEST(ContactCache, ReorderedInsertedAndRemovedManifoldsMatchByKeyAsBruteForce) {
    // Last step's manifolds read in order where the order holds, through the hash table where it does not: a step
    // that drops some pairs, adds new ones and reverses a run must carry exactly what a search by pair finds.
    BodyStorage storage;
    std::uint32_t dense;
    for (int i = 0; i < 400; ++i) storage.allocate(BodySet::Moving, dense);
    TaskPool pool(2);
    std::vector<ContactPair> first;
    for (std::uint32_t a = 0; a < 400; ++a)
        for (std::uint32_t b = a + 1; b < 400 && first.size() < 6000; b += 7) first.push_back({a, b, false, false});
    Contacts before;
    for (const ContactPair& p : first) {
        before.pairs.push_back(p);
        before.manifolds.push_back(manifoldWith({p.a % 4, 10 + p.b % 3}));
    }
    ContactCache cache;
    std::vector<PointImpulse> impulses;
    cache.warmStart(before, storage, pool, impulses);
    for (std::size_t k = 0; k < impulses.size(); ++k) impulses[k] = {float(k), float(k) + 0.5f, -float(k)};
    cache.remember(before, impulses, pool);
    const std::vector<PointImpulse> remembered = impulses;

    std::vector<ContactPair> second;
    for (std::size_t k = 0; k < first.size(); ++k) {
        if (k % 7 == 3) continue;  // separated
        if (k % 11 == 5 && first[k].b + 3 < 400)
            second.push_back({first[k].a, first[k].b + 3, false, false});  // a new pair
        second.push_back(first[k]);
    }
    std::reverse(second.begin() + 1000, second.begin() + 1300);
    Contacts after;
    for (const ContactPair& p : second) {
        after.pairs.push_back(p);
        after.manifolds.push_back(manifoldWith({p.a % 4, 10 + p.b % 3}));
    }
    cache.warmStart(after, storage, pool, impulses);
    std::uint32_t matched = 0;
    for (std::size_t m = 0; m < second.size(); ++m) {
        const auto old = std::find_if(first.begin(), first.end(),
                                      [&](const ContactPair& p) { return p.a == second[m].a && p.b == second[m].b; });
        for (int i = 0; i < kMaxManifoldPoints; ++i) {
            const PointImpulse expected = old == first.end() || i >= 2
                                              ? PointImpulse{}
                                              : remembered[std::size_t(old - first.begin()) * kMaxManifoldPoints + i];
            const PointImpulse& got = impulses[m * kMaxManifoldPoints + i];
            ASSERT_EQ(got.normal, expected.normal) << "manifold " << m << " point " << i;
            ASSERT_EQ(got.tangent1, expected.tangent1);
            ASSERT_EQ(got.tangent2, expected.tangent2);
        }
        matched += old != first.end() ? 1 : 0;
    }
    EXPECT_EQ(cache.matchedManifolds(), matched);
    EXPECT_GT(matched, 4000u);
    EXPECT_LT(matched, second.size());  // some pairs are new: the table's misses are exercised too
}

TEST(ContactCache, AManifoldMovedFarInTheOrderStillCarriesItsImpulses) {
    // A few changes (one manifold moves from near the front to near the back of 300, one pair is new): too few for
    // the hash table, so the moved manifold is found among the entries the in-order pass left.
    BodyStorage storage;
    std::uint32_t dense;
    for (int i = 0; i < 302; ++i) storage.allocate(BodySet::Moving, dense);
    TaskPool pool(2);
    Contacts before;
    for (std::uint32_t i = 0; i < 300; ++i) {
        before.pairs.push_back({i, i + 1, false, false});
        before.manifolds.push_back(manifoldWith({1, 2}));
    }
    ContactCache cache;
    std::vector<PointImpulse> impulses;
    cache.warmStart(before, storage, pool, impulses);
    for (std::size_t k = 0; k < impulses.size(); ++k) impulses[k].normal = float(k);
    cache.remember(before, impulses, pool);

    Contacts after = before;
    std::rotate(after.pairs.begin() + 5, after.pairs.begin() + 6, after.pairs.begin() + 290);  // pair 5 moves to 289
    after.pairs.push_back({300, 301, false, false});
    after.manifolds.push_back(manifoldWith({1, 2}));
    cache.warmStart(after, storage, pool, impulses);
    EXPECT_EQ(cache.matchedManifolds(), 300u);
    EXPECT_EQ(impulses[289 * kMaxManifoldPoints].normal, float(5 * kMaxManifoldPoints));
    EXPECT_EQ(impulses[289 * kMaxManifoldPoints + 1].normal, float(5 * kMaxManifoldPoints + 1));
    EXPECT_EQ(impulses[5 * kMaxManifoldPoints].normal, float(6 * kMaxManifoldPoints));
    EXPECT_EQ(impulses[300 * kMaxManifoldPoints].normal, 0.0f);
}
