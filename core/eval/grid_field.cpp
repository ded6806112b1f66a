// Trilinear interpolation of a sampled grid (the interpolant whose topology Marching Cubes 33 is
// defined against: Chernyaev 1995; Custodio, Etiene, Pesco and Silva 2013), with enclosures from
// the convex-combination property: inside a cell the interpolant, and each partial derivative (a
// bilinear blend of the cell's edge differences), lie between the smallest and largest of the
// values they blend.
#include "eval/grid_field.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <limits>
#include <stdexcept>

namespace isomesh {

namespace {

constexpr std::size_t kHeaderBytes = 36;
constexpr int kMaxSamplesPerAxis = 65536;
/// Rounding slack of the interpolation, relative to the largest value blended (a few roundings of
/// at most half an ulp each, with margin).
constexpr double kSlack = 16 * std::numeric_limits<double>::epsilon();
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

std::optional<IsoGrid> fail(std::string* error, std::string message) {
    if (error) *error = std::move(message);
    return std::nullopt;
}

std::uint32_t little_endian_u32(const unsigned char* bytes) {
    return std::uint32_t{bytes[0]} | std::uint32_t{bytes[1]} << 8 | std::uint32_t{bytes[2]} << 16 |
           std::uint32_t{bytes[3]} << 24;
}

std::string check_axis_count(char axis, long long n) {
    if (n >= 2 && n <= kMaxSamplesPerAxis) return {};
    return std::string("n") + axis + " = " + std::to_string(n) + " is not in [2, " +
           std::to_string(kMaxSamplesPerAxis) + "]";
}

/// Where a coordinate falls along one axis: the cell (0 .. n - 2) and the position t in [0, 1]
/// inside it. On a face between cells, the cell on the positive side (the last cell at the end).
struct AxisPosition {
    std::size_t cell;
    double t;
};

/// Grid geometry and samples, shared by all evaluators of a field.
struct Grid {
    IsoGrid iso;
    glm::dvec3 step;

    explicit Grid(IsoGrid g) : iso(std::move(g)) {
        glm::dvec3 intervals(iso.nx - 1, iso.ny - 1, iso.nz - 1);
        step = iso.box.size() / intervals;
    }

    int count(int axis) const { return axis == 0 ? iso.nx : axis == 1 ? iso.ny : iso.nz; }

    AxisPosition locate(int axis, double v) const {
        double u = (v - iso.box.lo[axis]) / step[axis];
        double cell = std::clamp(std::floor(u), 0.0, static_cast<double>(count(axis) - 2));
        return {static_cast<std::size_t>(cell), std::clamp(u - cell, 0.0, 1.0)};
    }

    double sample(std::size_t i, std::size_t j, std::size_t k) const {
        const std::size_t nx = static_cast<std::size_t>(iso.nx);
        const std::size_t ny = static_cast<std::size_t>(iso.ny);
        return iso.samples[i + nx * (j + ny * k)];
    }
};

double lerp(double a, double b, double t) {
    return (1.0 - t) * a + t * b;
}  // exact at t = 0, 1

/// The 8 samples of a cell, v[dk][dj][di], and the point's position in it.
struct Cell {
    double v[2][2][2];
    double tx, ty, tz;
};

Cell cell_at(const Grid& grid, const glm::dvec3& p) {
    AxisPosition x = grid.locate(0, p.x), y = grid.locate(1, p.y), z = grid.locate(2, p.z);
    Cell c{{}, x.t, y.t, z.t};
    for (int dk = 0; dk < 2; ++dk)
        for (int dj = 0; dj < 2; ++dj)
            for (int di = 0; di < 2; ++di)
                c.v[dk][dj][di] = grid.sample(x.cell + di, y.cell + dj, z.cell + dk);
    return c;
}

double interpolate(const Cell& c) {
    const auto& v = c.v;
    double lower =
        lerp(lerp(v[0][0][0], v[0][0][1], c.tx), lerp(v[0][1][0], v[0][1][1], c.tx), c.ty);
    double upper =
        lerp(lerp(v[1][0][0], v[1][0][1], c.tx), lerp(v[1][1][0], v[1][1][1], c.tx), c.ty);
    return lerp(lower, upper, c.tz);
}

glm::dvec3 derivative(const Cell& c, const glm::dvec3& step) {
    const auto& v = c.v;
    double dx = lerp(lerp(v[0][0][1] - v[0][0][0], v[0][1][1] - v[0][1][0], c.ty),
                     lerp(v[1][0][1] - v[1][0][0], v[1][1][1] - v[1][1][0], c.ty), c.tz);
    double dy = lerp(lerp(v[0][1][0] - v[0][0][0], v[0][1][1] - v[0][0][1], c.tx),
                     lerp(v[1][1][0] - v[1][0][0], v[1][1][1] - v[1][0][1], c.tx), c.tz);
    double dz = lerp(lerp(v[1][0][0] - v[0][0][0], v[1][0][1] - v[0][0][1], c.tx),
                     lerp(v[1][1][0] - v[0][1][0], v[1][1][1] - v[0][1][1], c.tx), c.ty);
    return glm::dvec3(dx, dy, dz) / step;
}

/// [lo, hi] widened by the interpolation's rounding slack.
Interval widened(double lo, double hi) {
    double slack = kSlack * std::max(std::fabs(lo), std::fabs(hi));
    return {lo - slack, hi + slack};
}

/// The sample index ranges [first, last] of the cells a (clipped) box overlaps, per axis.
struct SampleRange {
    std::size_t first[3], last[3];
};

class GridEvaluator final : public Evaluator {
  public:
    explicit GridEvaluator(std::shared_ptr<const Grid> grid) : grid_(std::move(grid)) {}

    double value(const glm::dvec3& p) override {
        if (!grid_->iso.box.contains(p)) return kNaN;
        return interpolate(cell_at(*grid_, p));
    }

    void values(const PointBatch& points, std::span<double> out) override {
        for (std::size_t i = 0; i < points.size(); ++i)
            out[i] = value({points.x[i], points.y[i], points.z[i]});
    }

    IntervalValue interval(const Box& box) override {
        std::optional<SampleRange> range = overlap(box);
        if (!range) return {Interval::empty(), false, true};
        double lo = std::numeric_limits<double>::infinity(), hi = -lo;
        for_each_sample(*range, [&](std::size_t i, std::size_t j, std::size_t k) {
            double s = grid_->sample(i, j, k);
            lo = std::min(lo, s);
            hi = std::max(hi, s);
        });
        return {widened(lo, hi), false, leaves_grid(box)};
    }

    ValueGradient value_gradient(const glm::dvec3& p) override {
        if (!grid_->iso.box.contains(p)) return {kNaN, glm::dvec3(kNaN)};
        Cell c = cell_at(*grid_, p);
        return {interpolate(c), derivative(c, grid_->step)};
    }

    IntervalGradient interval_gradient(const Box& box) override {
        IntervalGradient result{interval(box), {}};
        std::optional<SampleRange> range = overlap(box);
        for (int axis = 0; axis < 3; ++axis) {
            result.gradient[axis] = range ? edge_slopes(*range, axis) : Interval::empty();
        }
        return result;
    }

  private:
    bool leaves_grid(const Box& box) const {
        const Box& g = grid_->iso.box;
        return !(g.contains(box.lo) && g.contains(box.hi));
    }

    /// The samples of the cells `box` overlaps, or nullopt when it misses the grid.
    std::optional<SampleRange> overlap(const Box& box) const {
        const Box& g = grid_->iso.box;
        SampleRange range;
        for (int axis = 0; axis < 3; ++axis) {
            double lo = std::max(box.lo[axis], g.lo[axis]);
            double hi = std::min(box.hi[axis], g.hi[axis]);
            if (!(lo <= hi)) return std::nullopt;
            range.first[axis] = grid_->locate(axis, lo).cell;
            range.last[axis] = grid_->locate(axis, hi).cell + 1;
        }
        return range;
    }

    template <class Visit>
    static void for_each_sample(const SampleRange& r, const Visit& visit) {
        for (std::size_t k = r.first[2]; k <= r.last[2]; ++k)
            for (std::size_t j = r.first[1]; j <= r.last[1]; ++j)
                for (std::size_t i = r.first[0]; i <= r.last[0]; ++i) visit(i, j, k);
    }

    /// Bounds of the partial derivative along `axis` over the cells of `range`: the hull of the
    /// cells' edge differences along that axis, divided by the cell size.
    Interval edge_slopes(SampleRange range, int axis) const {
        range.last[axis] -= 1;  // edges start at the samples before the last
        double lo = std::numeric_limits<double>::infinity(), hi = -lo;
        for_each_sample(range, [&](std::size_t i, std::size_t j, std::size_t k) {
            std::size_t next[3] = {i, j, k};
            next[axis] += 1;
            double d = grid_->sample(next[0], next[1], next[2]) - grid_->sample(i, j, k);
            lo = std::min(lo, d);
            hi = std::max(hi, d);
        });
        return widened(lo / grid_->step[axis], hi / grid_->step[axis]);
    }

    std::shared_ptr<const Grid> grid_;
};

class GridField final : public Field {
  public:
    explicit GridField(IsoGrid grid) : grid_(std::make_shared<const Grid>(std::move(grid))) {}
    std::unique_ptr<Evaluator> make_evaluator() const override {
        return std::make_unique<GridEvaluator>(grid_);
    }
    Box domain() const override { return grid_->iso.box; }

  private:
    std::shared_ptr<const Grid> grid_;
};

}  // namespace

std::string validate_grid(const IsoGrid& grid) {
    for (auto [axis, n] : {std::pair{'x', grid.nx}, {'y', grid.ny}, {'z', grid.nz}}) {
        if (std::string error = check_axis_count(axis, n); !error.empty()) return error;
    }
    for (int axis = 0; axis < 3; ++axis) {
        double lo = grid.box.lo[axis], hi = grid.box.hi[axis];
        if (!(std::isfinite(lo) && std::isfinite(hi) && lo < hi))
            return "the grid's box is empty or not finite along " + std::string(1, "xyz"[axis]);
    }
    std::size_t expected = static_cast<std::size_t>(grid.nx) * static_cast<std::size_t>(grid.ny) *
                           static_cast<std::size_t>(grid.nz);
    if (grid.samples.size() != expected) {
        return "the grid has " + std::to_string(grid.samples.size()) +
               " samples, not nx*ny*nz = " + std::to_string(expected);
    }
    auto bad = std::find_if(grid.samples.begin(), grid.samples.end(),
                            [](float s) { return !std::isfinite(s); });
    if (bad != grid.samples.end())
        return "sample " + std::to_string(bad - grid.samples.begin()) + " is not finite";
    return {};
}

std::optional<IsoGrid> load_iso(const std::string& path, std::string* error) {
    std::ifstream in(path, std::ios::binary);
    if (!in) return fail(error, "cannot open '" + path + "'");
    in.seekg(0, std::ios::end);
    const std::streamoff file_size = in.tellg();
    in.seekg(0, std::ios::beg);
    unsigned char header[kHeaderBytes];
    if (file_size < static_cast<std::streamoff>(kHeaderBytes) ||
        !in.read(reinterpret_cast<char*>(header), kHeaderBytes)) {
        return fail(error, "'" + path + "' is truncated: its 36-byte header is incomplete");
    }
    IsoGrid grid;
    int* counts[3] = {&grid.nx, &grid.ny, &grid.nz};
    for (int axis = 0; axis < 3; ++axis) {
        *counts[axis] = std::bit_cast<std::int32_t>(little_endian_u32(header + 4 * axis));
        if (std::string e = check_axis_count("xyz"[axis], *counts[axis]); !e.empty())
            return fail(error, "'" + path + "': " + e);
    }
    for (int axis = 0; axis < 3; ++axis) {
        grid.box.lo[axis] = std::bit_cast<float>(little_endian_u32(header + 12 + 8 * axis));
        grid.box.hi[axis] = std::bit_cast<float>(little_endian_u32(header + 16 + 8 * axis));
    }
    const std::size_t count = static_cast<std::size_t>(grid.nx) *
                              static_cast<std::size_t>(grid.ny) * static_cast<std::size_t>(grid.nz);
    const std::streamoff expected = static_cast<std::streamoff>(kHeaderBytes + 4 * count);
    if (file_size != expected) {
        return fail(error, "'" + path + "' has " + std::to_string(file_size) + " bytes, but a " +
                               std::to_string(grid.nx) + "x" + std::to_string(grid.ny) + "x" +
                               std::to_string(grid.nz) + " grid takes " + std::to_string(expected) +
                               (file_size < expected ? " (truncated)" : " (trailing bytes)"));
    }
    std::vector<unsigned char> data(4 * count);
    if (!in.read(reinterpret_cast<char*>(data.data()), static_cast<std::streamsize>(data.size())))
        return fail(error, "'" + path + "': read error");
    grid.samples.resize(count);
    for (std::size_t i = 0; i < count; ++i)
        grid.samples[i] = std::bit_cast<float>(little_endian_u32(data.data() + 4 * i));
    if (std::string e = validate_grid(grid); !e.empty()) return fail(error, "'" + path + "': " + e);
    return grid;
}

std::shared_ptr<const Field> make_grid_field(IsoGrid grid) {
    if (std::string error = validate_grid(grid); !error.empty())
        throw std::invalid_argument("make_grid_field: " + error);
    return std::make_shared<GridField>(std::move(grid));
}

}  // namespace isomesh
