#include "server/first_mesh_cache.h"

#include <cstring>
#include <functional>

namespace isomesh::server {
namespace {

/// Requests whose key would be longer are not kept (a .vm program of thousands of operations is
/// rarely opened twice, and its key alone would weigh as much as a first mesh).
constexpr std::size_t kMaxKeyBytes = 64 << 10;

template <class T>
void append_bits(std::string& key, const T& value) {
    char bytes[sizeof(T)];
    std::memcpy(bytes, &value, sizeof(T));
    key.append(bytes, sizeof(T));
}

void append_text(std::string& key, const std::string& text) {
    append_bits(key, text.size());
    key += text;
}

}  // namespace

std::optional<std::string> first_mesh_key(const FunctionVersion& version, unsigned protocols) {
    const Tape& tape = *version.tape;
    const protocol::SessionState& state = version.state;
    std::string key;
    append_bits(key, protocols);
    append_bits(key, state.version);
    // The compiled function, instruction by instruction (constants by their bits).
    append_bits(key, tape.code.size());
    for (const Instruction& i : tape.code) {
        append_bits(key, i.op);
        append_bits(key, i.a);
        append_bits(key, i.b);
        append_bits(key, i.imm);
    }
    if (key.size() > kMaxKeyBytes) return std::nullopt;
    append_bits(key, tape.params.size());
    for (const std::string& name : tape.params) {
        append_text(key, name);
        const auto value = state.parameters.find(name);
        append_bits(key, value == state.parameters.end() ? 0.0 : value->second);
    }
    for (double bound : state.box) append_bits(key, bound);
    const protocol::Constraints& c = state.constraints;
    append_bits(key, c.triangles.value_or(0));
    append_bits(key, c.max_error.value_or(0.0));
    append_text(key, c.error_measure.value_or(""));
    return key;
}

void measure(FirstMesh& first, const std::string& key) {
    // Hash-table entries cost about twice their payload; the rest is vectors.
    const std::uint64_t triangles = first.mesh.mesh.triangle_count();
    const std::uint64_t vertices = first.mesh.mesh.vertex_count();
    std::uint64_t bytes = key.size() + sizeof(FirstMesh);
    bytes += triangles * (3 * 4 + 3 * 4 + 1 + 4) + vertices * (2 * 24 + 8 + 4);  // the mesh
    bytes += first.wire.triangle_count() * 2 * 32 + first.wire.vertex_count() * 2 * 32;
    bytes += first.wire_v2.triangle_count() * 2 * (24 + 2 * 16) + vertices * 2 * (32 + 24);
    for (const auto& frame : first.keyframes) bytes += frame ? frame->size() : 0;
    first.bytes = bytes;
}

std::shared_ptr<const FirstMesh> FirstMeshCache::find(const std::string& key) {
    std::lock_guard lock(mutex_);
    const auto it = slots_.find(key);
    if (it == slots_.end()) return nullptr;
    order_.splice(order_.begin(), order_, it->second.position);
    return it->second.first;
}

bool FirstMeshCache::seen_before(const std::string& key) {
    const std::size_t hash = std::hash<std::string>()(key);
    std::lock_guard lock(mutex_);
    if (seen_.contains(hash)) return true;
    if (seen_.size() >= 4 * max_entries_) seen_.clear();
    seen_.insert(hash);
    return false;
}

void FirstMeshCache::insert(const std::string& key, std::shared_ptr<const FirstMesh> first) {
    if (first->bytes > max_bytes_ || max_entries_ == 0) return;
    std::lock_guard lock(mutex_);
    if (const auto it = slots_.find(key); it != slots_.end()) {
        bytes_ -= it->second.first->bytes;
        order_.erase(it->second.position);
        slots_.erase(it);
    }
    order_.push_front(key);
    bytes_ += first->bytes;
    slots_.emplace(key, Slot{std::move(first), order_.begin()});
    evict_beyond_bounds();
}

void FirstMeshCache::evict_beyond_bounds() {
    while (!order_.empty() && (slots_.size() > max_entries_ || bytes_ > max_bytes_)) {
        const auto it = slots_.find(order_.back());
        bytes_ -= it->second.first->bytes;
        slots_.erase(it);
        order_.pop_back();
    }
}

std::size_t FirstMeshCache::entries() const {
    std::lock_guard lock(mutex_);
    return slots_.size();
}

std::uint64_t FirstMeshCache::bytes() const {
    std::lock_guard lock(mutex_);
    return bytes_;
}

}  // namespace isomesh::server
