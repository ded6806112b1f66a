#include "load_mix.h"

#include <cmath>
#include <fstream>
#include <random>
#include <sstream>
#include <stdexcept>

#include <nlohmann/json.hpp>

namespace isomesh::load {

const std::string_view kDefaultMixJson = R"mix([
  {"name": "bumpy sphere (thesis)", "expression": "x^2+y^2+z^2+2cos(2x)=5",
   "box": [-3, 3, -3, 3, -3, 3]},
  {"name": "sphere, radius slider", "expression": "x^2+y^2+z^2=a", "parameters": {"a": 4},
   "box": [-3, 3, -3, 3, -3, 3], "slider": {"parameter": "a", "min": 2, "max": 6}},
  {"name": "ellipsoid (thesis)", "expression": "10x^2+y^2+z^2=20", "box": [-5, 5, -5, 5, -5, 5]},
  {"name": "torus, tube slider", "expression": "(sqrt(x^2+y^2)-R)^2+z^2=r^2",
   "parameters": {"R": 2, "r": 0.7}, "box": [-3.2, 3.2, -3.2, 3.2, -1.2, 1.2],
   "slider": {"parameter": "r", "min": 0.4, "max": 0.9}},
  {"name": "tanglecube", "expression": "x^4-5x^2+y^4-5y^2+z^4-5z^2+11.8=0",
   "box": [-3, 3, -3, 3, -3, 3]},
  {"name": "gyroid, level slider", "expression": "sin(x)cos(y)+sin(y)cos(z)+sin(z)cos(x)=t",
   "parameters": {"t": 0}, "box": [-6, 6, -6, 6, -6, 6],
   "slider": {"parameter": "t", "min": -0.6, "max": 0.6}}
])mix";

namespace {

using nlohmann::json;

std::runtime_error entry_error(std::size_t index, const std::string& problem) {
    return std::runtime_error("mix entry " + std::to_string(index + 1) + ": " + problem);
}

Slider parse_slider(const json& value, const protocol::Create& create, std::size_t index) {
    if (!value.is_object() || !value.contains("parameter") || !value["parameter"].is_string() ||
        !value.contains("min") || !value["min"].is_number() || !value.contains("max") ||
        !value["max"].is_number() || value.size() != 3) {
        throw entry_error(index,
                          "\"slider\" must be {\"parameter\": NAME, \"min\": X, \"max\": Y}");
    }
    Slider slider{value["parameter"], value["min"], value["max"]};
    if (!(std::isfinite(slider.min) && std::isfinite(slider.max) && slider.min < slider.max)) {
        throw entry_error(index, "slider min must be below max");
    }
    if (!create.parameters.contains(slider.parameter)) {
        throw entry_error(index, "the slider's parameter '" + slider.parameter +
                                     "' needs a starting value in \"parameters\"");
    }
    return slider;
}

MixEntry parse_entry(json value, std::size_t index) {
    if (!value.is_object()) throw entry_error(index, "expected a JSON object");
    MixEntry entry;
    entry.name = "entry " + std::to_string(index + 1);
    if (value.contains("name")) {
        if (!value["name"].is_string()) throw entry_error(index, "\"name\" must be a string");
        entry.name = value["name"];
        value.erase("name");
    }
    if (value.contains("weight")) {
        const json& weight = value["weight"];
        if (!weight.is_number_unsigned() || weight.get<std::uint64_t>() < 1 ||
            weight.get<std::uint64_t>() > 1000) {
            throw entry_error(index, "\"weight\" must be an integer from 1 to 1000");
        }
        entry.weight = weight.get<unsigned>();
        value.erase("weight");
    }
    json slider;
    if (value.contains("slider")) {
        slider = value["slider"];
        value.erase("slider");
    }
    // The rest is a create request: the protocol library checks it as a server would.
    value["v"] = protocol::kProtocolVersion;
    value["type"] = "create";
    auto parsed = protocol::parse_client_message(value.dump());
    if (!parsed) throw entry_error(index, parsed.error().error.message);
    entry.create = std::get<protocol::Create>(parsed.value());
    if (!slider.is_null()) entry.slider = parse_slider(slider, entry.create, index);
    return entry;
}

}  // namespace

Mix parse_mix(std::string_view json_text) {
    const json document = json::parse(json_text, nullptr, false);
    if (document.is_discarded()) throw std::runtime_error("mix: not valid JSON");
    if (!document.is_array() || document.empty()) {
        throw std::runtime_error("mix: expected a non-empty JSON array of create requests");
    }
    Mix mix;
    for (std::size_t i = 0; i < document.size(); ++i) mix.push_back(parse_entry(document[i], i));
    return mix;
}

Mix default_mix() {
    return parse_mix(kDefaultMixJson);
}

Mix load_mix_file(const std::string& path) {
    std::ifstream file(path);
    if (!file) throw std::runtime_error("cannot read mix file " + path);
    std::ostringstream text;
    text << file.rdbuf();
    try {
        return parse_mix(text.str());
    } catch (const std::runtime_error& error) {
        throw std::runtime_error(path + ": " + error.what());
    }
}

const MixEntry& mix_entry(const Mix& mix, std::size_t user, std::size_t users, std::size_t round) {
    std::size_t total_weight = 0;
    for (const MixEntry& entry : mix) total_weight += entry.weight;
    std::size_t slot = (user + round * users) % total_weight;
    for (const MixEntry& entry : mix) {
        if (slot < entry.weight) return entry;
        slot -= entry.weight;
    }
    return mix.back();  // unreachable: slot < total_weight
}

MixEntry jittered(const MixEntry& entry, double jitter, std::uint64_t seed) {
    std::mt19937_64 random(seed);
    std::uniform_real_distribution<double> unit(-1.0, 1.0);
    MixEntry out = entry;
    for (auto& [name, value] : out.create.parameters)
        value += jitter * unit(random) * std::max(std::abs(value), 1.0);
    protocol::Box& box = out.create.box;
    for (int axis = 0; axis < 3; ++axis) {
        const double size = box[2 * axis + 1] - box[2 * axis];
        box[2 * axis] -= jitter * 0.5 * (1.0 + unit(random)) * size;
        box[2 * axis + 1] += jitter * 0.5 * (1.0 + unit(random)) * size;
    }
    return out;
}

}  // namespace isomesh::load
