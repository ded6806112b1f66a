// The grid peers of bench_pipeline: a uniform-grid mesher sampling f natively, and the search for
// the grid with a given triangle count or rms distance to the surface (each grid meshed once).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <functional>
#include <map>
#include <stdexcept>
#include <vector>

#include "bench_clock.h"
#include "eval/evaluator.h"
#include "grid_baseline.h"
#include "mesh/mesh.h"
#include "mesh/topology.h"
#include "refine/error_measures.h"

namespace isomesh::bench {

constexpr int kSamplesPerEdge = 3;  // 10 samples per triangle
constexpr std::size_t kMeasuredTriangles = 20'000;

/// A uniform-grid mesher sampling f natively: (n + 1)^3 samples for n cells per axis.
struct Peer {
    const char* name;
    Mesh (*mesh)(NativeBatch f, const Box& box, int cells, GridTimes* times);
    int max_cells;  // the searches stop there (memory: vtk keeps every sample, grid four planes)
};

inline double median(std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return v.empty() ? 0.0 : v[v.size() / 2];
}

/// Runs `run` (which returns its seconds) up to `runs` times, fewer when one takes over a
/// second; the median.
inline double timed(int runs, const std::function<double()>& run) {
    std::vector<double> seconds;
    double total = 0.0;
    for (int r = 0; r < runs && (r == 0 || total < 1.0); ++r) {
        seconds.push_back(run());
        total += seconds.back();
    }
    return median(seconds);
}

/// The area-weighted rms distance to the surface, on at most kMeasuredTriangles triangles
/// (every k-th: the grids' triangles come slab by slab, so they spread over the whole surface).
inline double rms_distance(const Mesh& mesh, Evaluator& evaluator) {
    const std::size_t stride =
        (mesh.triangle_count() + kMeasuredTriangles - 1) / kMeasuredTriangles;
    if (stride <= 1) return measure_mesh_error(mesh, evaluator, kSamplesPerEdge).rms_distance;
    Mesh sample;
    sample.positions = mesh.positions;
    sample.normals = mesh.normals;
    for (std::size_t t = 0; t < mesh.triangle_count(); t += stride)
        sample.triangles.push_back(mesh.triangles[t]);
    return measure_mesh_error(sample, evaluator, kSamplesPerEdge).rms_distance;
}

struct GridRun {
    int cells = 0;  // 0: no grid (none up to the peer's max_cells)
    std::size_t triangles = 0;
    double seconds = 0.0;  // sampling + meshing, thread CPU, median
    GridTimes split;       // of one run
    double rms = 0.0;
    TopologyReport topology;
};

/// One peer's grids of one case, each mesh made once for its triangle count and rms distance
/// (only the last few are kept: the large ones take hundreds of megabytes).
class GridSearch {
  public:
    GridSearch(NativeBatch native, const Box& box, const Peer& peer, Evaluator& evaluator)
        : native_(native), box_(box), peer_(peer), evaluator_(evaluator) {}

    std::size_t triangles(int n) { return measured(n).triangles; }
    double rms(int n) { return measured(n).rms; }

    /// The grid whose triangle count is closest to `target` (the count grows about as n^2).
    int equal_triangles(std::size_t target) {
        int n = 32;
        for (int step = 0; step < 6; ++step) {
            const double t = double(std::max<std::size_t>(triangles(n), 1));
            const int next =
                std::clamp(int(std::lround(n * std::sqrt(double(target) / t))), 2, peer_.max_cells);
            if (next == n) break;
            n = next;
        }
        const auto gap = [&](int m) { return std::abs(double(triangles(m)) - double(target)); };
        while (n > 2 && gap(n - 1) < gap(n)) --n;
        while (n < peer_.max_cells && gap(n + 1) < gap(n)) ++n;
        return n;
    }

    /// The coarsest grid whose rms distance is at most `target` (within 2% of n), from a start
    /// at n (the rms distance falls about as n^-2: predicted, then bisected), or 0 if none up to
    /// the peer's max_cells.
    int equal_rms(double target, int n) {
        int fail = 1, pass = 0;  // the largest n known to fail, the smallest known to pass
        for (int tries = 0; tries < 12; ++tries) {
            const double r = rms(n);
            if (r <= target) {
                pass = pass == 0 ? n : std::min(pass, n);
            } else {
                fail = std::max(fail, n);
            }
            if (pass != 0 && pass - fail <= std::max(1, pass / 50)) return pass;
            const int predicted = int(std::ceil(n * std::sqrt(r / target)));
            if (pass == 0) {
                if (fail >= peer_.max_cells) return 0;
                n = std::min(peer_.max_cells, std::max(fail + 1, int(predicted * 1.03) + 1));
            } else if (fail <= 1 && predicted < pass && predicted > 2) {
                n = predicted;
            } else {
                n = (fail + pass) / 2;
            }
        }
        return pass;
    }

    GridRun timed_run(int n, int runs) {
        GridRun run;
        run.cells = n;
        run.triangles = triangles(n);
        run.rms = rms(n);
        run.topology = measured(n).topology;
        run.seconds = timed(runs, [&] {
            GridTimes times;
            const Mesh m = peer_.mesh(native_, box_, n, &times);
            if (m.triangle_count() != run.triangles) throw std::logic_error("grid not repeatable");
            run.split = times;
            return times.sampling + times.meshing;
        });
        return run;
    }

  private:
    struct Measured {
        std::size_t triangles = 0;
        double rms = 0.0;
        TopologyReport topology;
    };

    const Measured& measured(int n) {
        auto it = measured_.find(n);
        if (it != measured_.end()) return it->second;
        const Mesh mesh = peer_.mesh(native_, box_, n, nullptr);
        return measured_[n] = {mesh.triangle_count(), rms_distance(mesh, evaluator_),
                               analyze_topology(mesh)};
    }

    NativeBatch native_;
    Box box_;
    const Peer& peer_;
    Evaluator& evaluator_;
    std::map<int, Measured> measured_;
};

}  // namespace isomesh::bench
