#include "refine/array_memory.h"

#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "fixtures.h"
#include "refine/refiner.h"

namespace isomesh {
namespace {

constexpr std::size_t kMiB = std::size_t{1} << 20;

// Restores the process-wide limit, and frees what a test left kept.
class ArrayMemory : public ::testing::Test {
  protected:
    void SetUp() override { release_recycled_memory(); }
    void TearDown() override {
        set_recycled_memory_limit(kDefaultRecycledMemoryBytes);
        release_recycled_memory();
    }
};

const char* data_of(std::size_t bytes) {
    RecycledVector<char> array(bytes);
    return array.data();
}

TEST_F(ArrayMemory, a_freed_block_serves_the_next_array_of_its_size) {
    const char* first = data_of(3 * kMiB);
    EXPECT_EQ(recycled_memory().kept_bytes, 4 * kMiB);  // two huge pages
    const RecycledMemory before = recycled_memory();
    EXPECT_EQ(data_of(3 * kMiB + 1000), first);
    EXPECT_EQ(recycled_memory().reused_blocks, before.reused_blocks + 1);
    EXPECT_EQ(recycled_memory().fresh_blocks, before.fresh_blocks);
}

TEST_F(ArrayMemory, small_arrays_are_recycled_in_4_kB_pages) {
    const char* first = data_of(300 << 10);
    EXPECT_EQ(recycled_memory().kept_bytes, std::size_t{320} << 10);  // 64 kB steps
    EXPECT_EQ(data_of(310 << 10), first);
    // Below kRecycledArrayBytes arrays come from std::allocator.
    data_of(kRecycledArrayBytes - 1);
    EXPECT_EQ(recycled_memory().kept_bytes, std::size_t{320} << 10);
    // Just below kHugePageArrayBytes: 1 MB in 64 kB steps, in 4 kB pages (a huge-page block's
    // alignment, 2 MB, would not divide its size).
    data_of(kHugePageArrayBytes - 1);
    EXPECT_EQ(recycled_memory().kept_bytes, (std::size_t{320} << 10) + kHugePageArrayBytes);
}

TEST_F(ArrayMemory, a_block_over_a_quarter_larger_than_the_array_is_not_used) {
    data_of(8 * kMiB);
    const RecycledMemory before = recycled_memory();
    EXPECT_FALSE(recycled_block_kept(5 * kMiB));  // three huge pages, and 8 MB is more than 7.5
    data_of(5 * kMiB);
    EXPECT_EQ(recycled_memory().fresh_blocks, before.fresh_blocks + 1);
    EXPECT_TRUE(recycled_block_kept(7 * kMiB));  // four huge pages
    EXPECT_FALSE(recycled_block_kept(9 * kMiB));
}

TEST_F(ArrayMemory, keeps_at_most_its_limit_oldest_freed_first) {
    set_recycled_memory_limit(4 * kMiB);
    {
        RecycledVector<char> a(2 * kMiB), b(2 * kMiB), c(2 * kMiB);
        const char* kept_first = b.data();
        const char* kept_last = c.data();
        RecycledVector<char>().swap(a);
        RecycledVector<char>().swap(b);
        RecycledVector<char>().swap(c);  // a is freed to make room
        EXPECT_EQ(recycled_memory().kept_bytes, 4 * kMiB);
        // Of equal blocks, the one kept longest serves first (then goes back behind the other).
        EXPECT_EQ(data_of(2 * kMiB), kept_first);
        EXPECT_EQ(data_of(2 * kMiB), kept_last);
    }
    data_of(6 * kMiB);  // over the limit alone: freed at once
    EXPECT_LE(recycled_memory().kept_bytes, 4 * kMiB);
    set_recycled_memory_limit(0);
    EXPECT_EQ(recycled_memory().kept_bytes, 0u);
    data_of(2 * kMiB);
    EXPECT_EQ(recycled_memory().kept_bytes, 0u);
}

TEST_F(ArrayMemory, release_frees_every_kept_block) {
    data_of(2 * kMiB);
    data_of(6 * kMiB);
    EXPECT_EQ(recycled_memory().kept_bytes, 8 * kMiB);
    release_recycled_memory();
    EXPECT_EQ(recycled_memory().kept_bytes, 0u);
}

TEST_F(ArrayMemory, reservation_takes_the_whole_room_only_from_kept_blocks) {
    RecycledVector<double> array;
    reserve(array, Reservation(kMiB, 1000));  // 8 MB: nothing kept
    EXPECT_EQ(array.capacity(), 1000u);
    data_of(8 * kMiB);
    reserve(array, Reservation(kMiB, 1000));
    EXPECT_EQ(array.capacity(), kMiB);
    RecycledVector<double> small;
    reserve(small, Reservation(1000, 10));  // 8 kB, from std::allocator: not held for later
    EXPECT_EQ(small.capacity(), 10u);
}

TEST_F(ArrayMemory, make_room_doubles_but_stops_once_at_the_wanted_room) {
    RecycledVector<double> array;
    reserve(array, Reservation(3000, 1000));
    for (std::size_t size = 1; size <= 1000; ++size) make_room(array, size, 3000);
    EXPECT_EQ(array.capacity(), 1000u);  // room enough: no growth
    make_room(array, 1001, 3000);
    EXPECT_EQ(array.capacity(), 2000u);  // doubling
    make_room(array, 2001, 3000);
    EXPECT_EQ(array.capacity(), 3000u);  // not 4000: the wanted room
    make_room(array, 3001, 3000);
    EXPECT_EQ(array.capacity(), 6000u);  // past it: doubling again
    make_room(array, 7000, 3000);
    EXPECT_EQ(array.capacity(), 12000u);
}

TEST_F(ArrayMemory, an_array_grown_from_its_fallback_leaves_a_block_the_same_reservation_takes) {
    // 3 MB wanted, 0.8 MB reserved at first (a refiner that started small): grown element by
    // element as the pools grow, the array ends in a block of the wanted size, which the next
    // array with the same reservation gets whole (doubled from 0.8 MB it would have ended at
    // 6.4 MB, over 5/4 of 3 MB, and never been taken).
    const Reservation room(3 * kMiB / 8, 100'000);
    const double* first = nullptr;
    {
        RecycledVector<double> array;
        reserve(array, room);
        EXPECT_EQ(array.capacity(), 100'000u);
        for (std::size_t i = 0; i < room.wanted; ++i) {
            make_room(array, array.size() + 1, room.wanted);
            array.push_back(double(i));
        }
        EXPECT_EQ(array.capacity(), room.wanted);
        first = array.data();
    }
    const RecycledMemory before = recycled_memory();
    RecycledVector<double> next;
    reserve(next, room);
    EXPECT_EQ(next.capacity(), room.wanted);
    EXPECT_EQ(next.data(), first);
    EXPECT_EQ(recycled_memory().reused_blocks, before.reused_blocks + 1);
}

#if defined(__SANITIZE_ADDRESS__)
TEST_F(ArrayMemory, a_kept_block_is_poisoned_under_address_sanitizer) {
    char* stale = nullptr;
    {
        RecycledVector<char> array(2 * kMiB);
        stale = array.data();
    }
    EXPECT_GT(recycled_memory().kept_bytes, 0u);
    EXPECT_DEATH(static_cast<volatile char*>(stale)[0] = 1, "use-after-poison");
}
#endif

// A refinement whose arrays (about 10 MB) come fresh, recycled, and recycled while another runs
// beside it: the same deltas and the same mesh.
struct Refinement {
    std::vector<MeshDelta> deltas;
    Mesh mesh;
};

Refinement refine() {
    auto field = test::make_quadric_field({10, 1, 1}, 20);
    RefineSettings settings;
    settings.constraint = Constraint::triangle_budget(30000);
    Refiner refiner(field, test::cube_sphere_mesh(*field, 6), settings);
    Refinement r;
    for (;;) {
        StepResult step = refiner.step({4000});
        r.deltas.push_back(std::move(step.delta));
        if (step.converged) break;
    }
    refiner.set_constraint(Constraint::triangle_budget(9000));
    r.deltas.push_back(refiner.run_to_convergence().delta);
    r.mesh = test::canonical(refiner.mesh());
    return r;
}

void expect_same(const Refinement& a, const Refinement& b) {
    EXPECT_TRUE(test::same_mesh(a.mesh, b.mesh));
    ASSERT_EQ(a.deltas.size(), b.deltas.size());
    for (std::size_t i = 0; i < a.deltas.size(); ++i) {
        const MeshDelta &x = a.deltas[i], &y = b.deltas[i];
        EXPECT_EQ(x.removed_triangles, y.removed_triangles) << "delta " << i;
        EXPECT_EQ(x.removed_vertices, y.removed_vertices) << "delta " << i;
        ASSERT_EQ(x.added_vertices.size(), y.added_vertices.size()) << "delta " << i;
        for (std::size_t v = 0; v < x.added_vertices.size(); ++v) {
            EXPECT_EQ(x.added_vertices[v].id, y.added_vertices[v].id);
            EXPECT_EQ(x.added_vertices[v].position, y.added_vertices[v].position);
            EXPECT_EQ(x.added_vertices[v].normal, y.added_vertices[v].normal);
        }
        ASSERT_EQ(x.added_triangles.size(), y.added_triangles.size()) << "delta " << i;
        for (std::size_t t = 0; t < x.added_triangles.size(); ++t) {
            EXPECT_EQ(x.added_triangles[t].id, y.added_triangles[t].id);
            EXPECT_EQ(x.added_triangles[t].vertices, y.added_triangles[t].vertices);
        }
    }
}

TEST_F(ArrayMemory, refiners_on_recycled_memory_make_the_same_meshes) {
    set_recycled_memory_limit(0);
    const Refinement fresh = refine();
    set_recycled_memory_limit(kDefaultRecycledMemoryBytes);
    refine();  // leaves its blocks
    const RecycledMemory before = recycled_memory();
    const Refinement recycled = refine();
    EXPECT_GT(recycled_memory().reused_blocks, before.reused_blocks);
    expect_same(fresh, recycled);
    Refinement beside;
    std::thread other([&] { beside = refine(); });
    const Refinement here = refine();
    other.join();
    expect_same(fresh, here);
    expect_same(fresh, beside);
}

}  // namespace
}  // namespace isomesh
