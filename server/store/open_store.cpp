// --store values and opening the store they name.
#include <charconv>

#include "server/store/redis_store.h"
#include "server/store/session_store.h"
#include "server/store/sqlite_store.h"

namespace isomesh::server::store {

std::optional<StoreSpec> parse_store_spec(std::string_view text) {
    StoreSpec spec;
    if (text == "none") return spec;
    if (text.starts_with("sqlite:")) {
        spec.kind = StoreSpec::Kind::sqlite;
        spec.path = std::string(text.substr(7));
        if (spec.path.empty()) return std::nullopt;
        return spec;
    }
    if (text.starts_with("redis://")) {
        std::string_view address = text.substr(8);
        if (!address.empty() && address.back() == '/') address.remove_suffix(1);
        spec.kind = StoreSpec::Kind::redis;
        const auto colon = address.rfind(':');
        spec.host = std::string(address.substr(0, colon));
        if (colon != std::string_view::npos) {
            const std::string_view digits = address.substr(colon + 1);
            unsigned port = 0;
            auto [end, ec] = std::from_chars(digits.data(), digits.data() + digits.size(), port);
            if (ec != std::errc() || end != digits.data() + digits.size() || port == 0 ||
                port > 65535)
                return std::nullopt;
            spec.port = static_cast<std::uint16_t>(port);
        }
        if (spec.host.empty() || spec.host.find_first_of("/@?") != std::string::npos)
            return std::nullopt;
        return spec;
    }
    return std::nullopt;
}

StoreResult<std::unique_ptr<SessionStore>> open_store(const StoreSpec& spec,
                                                      std::uint32_t ttl_seconds) {
    switch (spec.kind) {
        case StoreSpec::Kind::none:
            return std::unique_ptr<SessionStore>();
        case StoreSpec::Kind::sqlite: {
            auto store = SqliteStore::open(spec.path);
            if (!store) return store.error();
            return std::unique_ptr<SessionStore>(std::move(store).value());
        }
        case StoreSpec::Kind::redis:
            return std::unique_ptr<SessionStore>(
                std::make_unique<RedisStore>(spec.host, spec.port, ttl_seconds));
    }
    return StoreError{"unknown store kind"};
}

}  // namespace isomesh::server::store
