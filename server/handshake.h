// Who may open a WebSocket, and with what request (RFC 6455, 4.2.1), checked before Beast
// accepts the upgrade: the Origin allow-list (a web page anywhere must not drive the server through
// its visitors' browsers) and a strict reading of the handshake.
#pragma once

#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace isomesh::server {

/// The origins allowed to open a WebSocket (ServerConfig::allow_origin): "*" for any, a list of
/// scheme://host[:port], or by default the server's own origin (same host as the request's Host
/// header) and loopback origins (localhost, 127.0.0.0/8, [::1]). A request without an Origin
/// header is not from a browser and is allowed: the check protects browsers' users, not the
/// server (any other client can send any header).
class OriginPolicy {
  public:
    /// `allow_list` as in ServerConfig::allow_origin.
    explicit OriginPolicy(std::string_view allow_list);
    bool allows(std::optional<std::string_view> origin, std::string_view host) const;

  private:
    bool any_ = false;
    std::vector<std::string> allowed_;  // lowercase, without a trailing '/'
};

/// Why a list given to --allow-origin is malformed, if it is.
std::optional<std::string> check_allow_origin(std::string_view allow_list);

/// The parts of an upgrade request the checks read.
struct UpgradeRequest {
    std::string_view method;
    unsigned version = 11;  ///< HTTP/1.1 = 11
    std::string_view host;
    std::string_view key;         ///< Sec-WebSocket-Key
    std::string_view ws_version;  ///< Sec-WebSocket-Version
    std::optional<std::string_view> origin;
};

struct HandshakeRefusal {
    unsigned status = 400;  ///< 400, 403 (origin) or 426 (version: the reply names 13)
    std::string message;
};

/// Why the upgrade must be refused, if it must: not GET over HTTP/1.1, no Host, a
/// Sec-WebSocket-Key that is not 16 bytes in base64, a Sec-WebSocket-Version other than 13, or an
/// Origin the policy does not allow.
std::optional<HandshakeRefusal> check_upgrade(const UpgradeRequest& request,
                                              const OriginPolicy& origins);

/// True when `key` is the base64 form of exactly 16 bytes (24 characters ending in "==").
bool valid_websocket_key(std::string_view key);

}  // namespace isomesh::server
