// Who may open a WebSocket (14.7) and a strict reading of the handshake (14.8).
#include "server/handshake.h"

#include <gtest/gtest.h>

namespace isomesh::server {
namespace {

UpgradeRequest upgrade(std::optional<std::string_view> origin = std::nullopt) {
    UpgradeRequest r;
    r.method = "GET";
    r.host = "mesh.example.org:8080";
    r.key = "dGhlIHNhbXBsZSBub25jZQ==";  // RFC 6455's example
    r.ws_version = "13";
    r.origin = origin;
    return r;
}

TEST(WebSocketKey, must_be_16_bytes_in_base64) {
    EXPECT_TRUE(valid_websocket_key("dGhlIHNhbXBsZSBub25jZQ=="));
    EXPECT_TRUE(valid_websocket_key("AAAAAAAAAAAAAAAAAAAAAA=="));
    for (const char* key :
         {"abc", "", "dGhlIHNhbXBsZSBub25jZQ", "dGhlIHNhbXBsZSBub25jZQ=",
          "dGhlIHNhbXBsZSBub25jZR==", "dGhlIHNhbXBsZSBub25j*Q==", "dGhlIHNhbXBsZSBub25jZQ==AAAA"})
        EXPECT_FALSE(valid_websocket_key(key)) << key;
}

TEST(OriginPolicy, default_allows_own_origin_loopback_and_non_browsers_only) {
    const OriginPolicy policy("");
    const std::string_view host = "mesh.example.org:8080";
    EXPECT_TRUE(policy.allows(std::nullopt, host));
    EXPECT_TRUE(policy.allows("http://mesh.example.org:8080", host));
    EXPECT_TRUE(policy.allows("https://MESH.example.org:8080", host));
    EXPECT_TRUE(policy.allows("http://localhost:5173", host));
    EXPECT_TRUE(policy.allows("http://127.0.0.1", host));
    EXPECT_TRUE(policy.allows("http://[::1]:3000", host));
    EXPECT_FALSE(policy.allows("https://evil.example", host));
    EXPECT_FALSE(policy.allows("http://mesh.example.org:9999", host));
    EXPECT_FALSE(policy.allows("http://localhost.evil.example", host));
    EXPECT_FALSE(policy.allows("null", host));
}

TEST(OriginPolicy, a_list_allows_exactly_its_origins_and_star_allows_any) {
    const OriginPolicy list("https://geogebra.example, http://localhost:5173/");
    EXPECT_TRUE(list.allows("https://geogebra.example", "h"));
    EXPECT_TRUE(list.allows("http://localhost:5173", "h"));
    EXPECT_FALSE(list.allows("http://localhost:5174", "h"));
    EXPECT_FALSE(list.allows("http://h", "h"));  // a list replaces the default
    EXPECT_TRUE(OriginPolicy("*").allows("https://anywhere.example", "h"));
}

TEST(OriginPolicy, malformed_lists_are_refused) {
    EXPECT_FALSE(check_allow_origin(""));
    EXPECT_FALSE(check_allow_origin("*"));
    EXPECT_FALSE(check_allow_origin("https://a.example,http://[::1]:80"));
    EXPECT_TRUE(check_allow_origin("a.example"));
    EXPECT_TRUE(check_allow_origin("https://a.example/path"));
    EXPECT_TRUE(check_allow_origin("ftp://a.example"));
}

TEST(CheckUpgrade, refuses_what_rfc_6455_and_the_policy_refuse) {
    const OriginPolicy policy("");
    EXPECT_FALSE(check_upgrade(upgrade(), policy));
    auto with = [&](auto change) {
        UpgradeRequest r = upgrade();
        change(r);
        auto refusal = check_upgrade(r, policy);
        return refusal ? refusal->status : 0u;
    };
    EXPECT_EQ(with([](UpgradeRequest& r) { r.key = "abc"; }), 400u);
    EXPECT_EQ(with([](UpgradeRequest& r) { r.key = ""; }), 400u);
    EXPECT_EQ(with([](UpgradeRequest& r) { r.method = "POST"; }), 400u);
    EXPECT_EQ(with([](UpgradeRequest& r) { r.version = 10; }), 400u);
    EXPECT_EQ(with([](UpgradeRequest& r) { r.host = ""; }), 400u);
    EXPECT_EQ(with([](UpgradeRequest& r) { r.ws_version = "8"; }), 426u);
    EXPECT_EQ(with([](UpgradeRequest& r) { r.origin = "https://evil.example"; }), 403u);
}

}  // namespace
}  // namespace isomesh::server
