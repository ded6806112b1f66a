#include "server/handshake.h"

#include <algorithm>
#include <cctype>

namespace isomesh::server {
namespace {

std::string lowercase(std::string_view text) {
    std::string out(text);
    std::transform(out.begin(), out.end(), out.begin(),
                   [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    return out;
}

std::string trim(std::string_view text) {
    const auto first = text.find_first_not_of(" \t");
    if (first == std::string_view::npos) return {};
    const auto last = text.find_last_not_of(" \t");
    return std::string(text.substr(first, last - first + 1));
}

/// The comma-separated entries of a list, trimmed, empty ones dropped.
std::vector<std::string> entries(std::string_view list) {
    std::vector<std::string> out;
    std::size_t start = 0;
    while (start <= list.size()) {
        std::size_t end = list.find(',', start);
        if (end == std::string_view::npos) end = list.size();
        std::string entry = trim(list.substr(start, end - start));
        if (!entry.empty()) out.push_back(std::move(entry));
        start = end + 1;
    }
    return out;
}

/// The host of "scheme://host[:port]" (brackets kept for IPv6), or nothing.
std::optional<std::string> origin_host(std::string_view origin) {
    const auto scheme_end = origin.find("://");
    if (scheme_end == std::string_view::npos) return std::nullopt;
    std::string_view rest = origin.substr(scheme_end + 3);
    if (rest.empty()) return std::nullopt;
    if (rest.front() == '[') {
        const auto close = rest.find(']');
        if (close == std::string_view::npos) return std::nullopt;
        return lowercase(rest.substr(0, close + 1));
    }
    return lowercase(rest.substr(0, rest.find(':')));
}

bool loopback_host(std::string_view host) {
    return host == "localhost" || host.starts_with("127.") || host == "[::1]";
}

std::string without_trailing_slash(std::string text) {
    while (!text.empty() && text.back() == '/') text.pop_back();
    return text;
}

}  // namespace

OriginPolicy::OriginPolicy(std::string_view allow_list) {
    for (const std::string& entry : entries(allow_list)) {
        if (entry == "*") any_ = true;
        allowed_.push_back(without_trailing_slash(lowercase(entry)));
    }
}

bool OriginPolicy::allows(std::optional<std::string_view> origin, std::string_view host) const {
    if (!origin || any_) return true;
    const std::string given = without_trailing_slash(lowercase(*origin));
    if (!allowed_.empty())
        return std::find(allowed_.begin(), allowed_.end(), given) != allowed_.end();
    const auto origin_name = origin_host(given);
    if (!origin_name) return false;
    if (loopback_host(*origin_name)) return true;
    // The server's own origin: a page it served itself, under the host the browser asked for.
    const std::string own = lowercase(host);
    return given == "http://" + own || given == "https://" + own;
}

std::optional<std::string> check_allow_origin(std::string_view allow_list) {
    for (const std::string& entry : entries(allow_list)) {
        if (entry == "*") continue;
        const std::string e = lowercase(entry);
        const bool scheme = e.starts_with("http://") || e.starts_with("https://");
        const auto host = origin_host(without_trailing_slash(e));
        const std::string_view rest = std::string_view(e).substr(e.find("://") + 3);
        if (!scheme || !host || host->empty() ||
            without_trailing_slash(std::string(rest)).find('/') != std::string::npos)
            return "'" + entry + "' is not an origin like https://example.org or " +
                   "http://localhost:5173";
    }
    return std::nullopt;
}

bool valid_websocket_key(std::string_view key) {
    if (key.size() != 24 || !key.ends_with("==")) return false;
    const auto base64 = [](char c) {
        return std::isalnum(static_cast<unsigned char>(c)) || c == '+' || c == '/';
    };
    if (!std::all_of(key.begin(), key.begin() + 22, base64)) return false;
    // 16 bytes are 128 bits: the 22nd character carries 2 bits and 4 zero bits (A, Q, g or w).
    const char last = key[21];
    return last == 'A' || last == 'Q' || last == 'g' || last == 'w';
}

std::optional<HandshakeRefusal> check_upgrade(const UpgradeRequest& request,
                                              const OriginPolicy& origins) {
    if (request.method != "GET" || request.version < 11)
        return HandshakeRefusal{400, "a WebSocket upgrade is a GET over HTTP/1.1"};
    if (trim(request.host).empty()) return HandshakeRefusal{400, "no Host header"};
    if (trim(request.ws_version) != "13")
        return HandshakeRefusal{426, "Sec-WebSocket-Version must be 13"};
    if (!valid_websocket_key(trim(request.key)))
        return HandshakeRefusal{400, "Sec-WebSocket-Key must be 16 bytes in base64"};
    if (!origins.allows(request.origin, request.host))
        return HandshakeRefusal{403,
                                "this origin may not open a WebSocket here (see the "
                                "server's --allow-origin)"};
    return std::nullopt;
}

}  // namespace isomesh::server
