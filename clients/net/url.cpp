// URL parsing for ws_client.h: the small subset of RFC 3986 the isomesh clients need.
#include <cctype>

#include "ws_client.h"

namespace isomesh::net {
namespace {

bool all_digits(std::string_view text) {
    if (text.empty()) return false;
    for (char c : text) {
        if (!std::isdigit(static_cast<unsigned char>(c))) return false;
    }
    return true;
}

}  // namespace

Url Url::with(std::string_view new_scheme, std::string_view new_target) const {
    Url url = *this;
    url.scheme = new_scheme;
    url.target = new_target;
    return url;
}

std::string Url::to_string() const {
    const std::string shown_host = host.find(':') != std::string::npos ? "[" + host + "]" : host;
    return scheme + "://" + shown_host + ":" + port + target;
}

Url parse_url(std::string_view text) {
    const auto fail = [&](std::string_view why) {
        return NetError("bad URL '" + std::string(text) + "': " + std::string(why));
    };
    Url url;
    const auto colon = text.find("://");
    if (colon == std::string_view::npos) throw fail("expected ws://HOST:PORT/PATH");
    url.scheme = text.substr(0, colon);
    if (url.scheme != "ws" && url.scheme != "http") throw fail("only ws:// and http:// are known");
    std::string_view rest = text.substr(colon + 3);
    const auto slash = rest.find('/');
    std::string_view authority = rest.substr(0, slash);
    url.target = slash == std::string_view::npos ? "/" : std::string(rest.substr(slash));
    if (url.target.find('#') != std::string::npos) throw fail("fragments are not supported");
    if (authority.find('@') != std::string_view::npos) throw fail("user info is not supported");
    std::string_view port;
    if (authority.starts_with('[')) {
        const auto close = authority.find(']');
        if (close == std::string_view::npos) throw fail("unclosed '[' in the host");
        url.host = authority.substr(1, close - 1);
        std::string_view after = authority.substr(close + 1);
        if (!after.empty() && !after.starts_with(':')) throw fail("junk after the host");
        if (!after.empty()) port = after.substr(1);
    } else {
        const auto port_colon = authority.rfind(':');
        url.host = authority.substr(0, port_colon);
        if (port_colon != std::string_view::npos) port = authority.substr(port_colon + 1);
    }
    if (url.host.empty()) throw fail("no host");
    if (port.empty()) {
        url.port = "80";
    } else if (!all_digits(port) || port.size() > 5 || std::stoul(std::string(port)) > 65535 ||
               std::stoul(std::string(port)) == 0) {
        throw fail("the port must be a number from 1 to 65535");
    } else {
        url.port = port;
    }
    return url;
}

}  // namespace isomesh::net
