#include "protocol/messages.h"
#include "protocol/request_id_scanner.h"

#include <gtest/gtest.h>

namespace isomesh::protocol {
namespace {

const SessionId kSession = *SessionId::from_hex("00112233445566778899aabbccddeeff");
const Box kBox = {-2, 2, -1, 1, -3, 3};
const std::string kHex = "00112233445566778899aabbccddeeff";

/// Concatenation by appending (GCC 12 warns falsely on chains of string operator+ at -O3).
std::string cat(std::initializer_list<std::string_view> parts) {
    std::string out;
    for (std::string_view part : parts) out.append(part);
    return out;
}

template <class Message>
void expect_client_round_trip(const Message& message) {
    const std::string text = serialize(ClientMessage(message));
    auto parsed = parse_client_message(text);
    ASSERT_TRUE(parsed) << text << ": " << parsed.error().error.message;
    ASSERT_TRUE(std::holds_alternative<Message>(parsed.value())) << text;
    EXPECT_EQ(std::get<Message>(parsed.value()), message) << text;
}

template <class Message>
void expect_server_round_trip(const Message& message) {
    const std::string text = serialize(ServerMessage(message));
    auto parsed = parse_server_message(text);
    ASSERT_TRUE(parsed) << text << ": " << parsed.error().message;
    ASSERT_TRUE(std::holds_alternative<Message>(parsed.value())) << text;
    EXPECT_EQ(std::get<Message>(parsed.value()), message) << text;
}

RequestError client_error(std::string_view text, const ParseLimits& limits = {}) {
    auto parsed = parse_client_message(text, limits);
    EXPECT_FALSE(parsed) << text;
    return parsed ? RequestError{} : parsed.error();
}

void expect_client_error(std::string_view text, ErrorCode code,
                         std::string_view message_part = "") {
    const RequestError error = client_error(text);
    EXPECT_EQ(error.error.code, code) << text << " -> " << error.error.message;
    EXPECT_NE(error.error.message.find(message_part), std::string::npos)
        << text << " -> " << error.error.message;
}

std::string request(std::string_view type, std::string_view fields = "") {
    return cat({R"({"v":1,"type":")", type, "\"", fields.empty() ? "" : ",", fields, "}"});
}

std::string with_session(std::string_view fields = "") {
    return cat({R"("session":")", kHex, "\"", fields.empty() ? "" : ",", fields});
}

TEST(SessionId, hex_round_trip_and_rejects) {
    EXPECT_EQ(kSession.to_hex(), kHex);
    EXPECT_EQ(SessionId::from_hex("00112233445566778899AABBCCDDEEFF"), kSession);
    EXPECT_FALSE(SessionId::from_hex("0011"));
    EXPECT_FALSE(SessionId::from_hex("g0112233445566778899aabbccddeeff"));
    EXPECT_FALSE(SessionId::from_hex(kHex + "00"));
}

TEST(ErrorCode, names_round_trip) {
    for (int i = 0; i < kErrorCodeCount; ++i) {
        const auto code = static_cast<ErrorCode>(i);
        EXPECT_EQ(error_code_from_string(to_string(code)), code);
    }
    EXPECT_EQ(to_string(ErrorCode::too_many_sessions), "too_many_sessions");
    EXPECT_FALSE(error_code_from_string("nope"));
}

TEST(Messages, client_messages_round_trip) {
    expect_client_round_trip(Create{7,
                                    {Source::Kind::expression, "x^2+y^2+z^2=a"},
                                    {{"a", 1.5}, {"b", -2}},
                                    kBox,
                                    {20000, 0.001, "epsilon4"}});
    expect_client_round_trip(Create{"req-1", {Source::Kind::vm, "_0 var-x\n"}, {}, kBox, {}});
    expect_client_round_trip(Update{std::nullopt, kSession, std::nullopt, Parameters{{"a", 3}},
                                    std::nullopt, std::nullopt});
    expect_client_round_trip(Update{-3, kSession, Source{Source::Kind::expression, "x=y"},
                                    Parameters{}, kBox, Constraints{10, std::nullopt, "distance"}});
    expect_client_round_trip(Subscribe{1, kSession});
    expect_client_round_trip(Unsubscribe{2, kSession});
    expect_client_round_trip(Pause{3, kSession});
    expect_client_round_trip(Resume{std::nullopt, kSession});
    expect_client_round_trip(Close{"c", kSession});
    expect_client_round_trip(Resync{5, kSession});
    expect_client_round_trip(Ping{std::int64_t{kMaxSafeInteger}});
    expect_client_round_trip(Ping{std::nullopt});
}

TEST(Messages, server_messages_round_trip) {
    const SessionState state{4, "x^2=a", {{"a", 2}}, kBox, {1000, 0.0, "epsilon4"}};
    const SessionState vm_state{1, std::nullopt, {}, kBox, {50, 0.5, "distance"}};
    expect_server_round_trip(Created{7, kSession, state});
    SessionId view = kSession;
    view.bytes[3] = 0x42;
    expect_server_round_trip(Created{7, kSession, state, view, Access::control});
    expect_server_round_trip(Subscribed{8, view, state, std::nullopt, Access::view});
    expect_server_round_trip(
        Pong{2, 5, ServerLimits{1 << 20, 16, 2'000'000, 1u << 30, 10.0, 3600.0, 3600.0, 30.0}});
    expect_server_round_trip(Updated{std::nullopt, kSession, vm_state});
    expect_server_round_trip(Subscribed{"s", kSession, state});
    expect_server_round_trip(Ack{9, MessageType::resync, kSession});
    expect_server_round_trip(Pong{1, 1'700'000'000'123'456});
    expect_server_round_trip(Progress{kSession, 2, 17, 5000, 0.25, 3.5, 125000.5});
    expect_server_round_trip(Converged{kSession, 2, 40, 20000, 0.01, 0.5, 9000, 12, 2.5, 40.25});
    expect_server_round_trip(
        ErrorReply{3, std::nullopt, ErrorCode::bad_expression, "unexpected ')' at column 12", 12});
    expect_server_round_trip(
        ErrorReply{std::nullopt, kSession, ErrorCode::eval_timeout, "too slow", std::nullopt});
    expect_server_round_trip(Closed{kSession, Closed::Reason::shutdown});
}

TEST(Messages, serialize_writes_version_and_type_first) {
    const std::string text = serialize(ClientMessage(Ping{42}));
    EXPECT_EQ(text, R"({"v":1,"type":"ping","id":42})");
}

TEST(Messages, parse_accepts_documented_create_example) {
    auto parsed = parse_client_message(
        R"({"v":1,"type":"create","id":1,"expression":"x^2+y^2+z^2+2cos(2x)=a",
            "parameters":{"a":5},"box":[-3,3,-3,3,-3,3],
            "constraints":{"triangles":20000,"max_error":0.001,"error_measure":"epsilon4"}})");
    ASSERT_TRUE(parsed) << parsed.error().error.message;
    const auto& create = std::get<Create>(parsed.value());
    EXPECT_EQ(create.id, RequestId(std::int64_t{1}));
    EXPECT_EQ(create.source.kind, Source::Kind::expression);
    EXPECT_EQ(create.parameters.at("a"), 5.0);
    EXPECT_EQ(create.box[1], 3.0);
    EXPECT_EQ(create.constraints.triangles, 20000u);
}

TEST(Messages, malformed_json_is_bad_json) {
    expect_client_error("", ErrorCode::bad_json, "invalid JSON");
    expect_client_error("{\"v\":1,", ErrorCode::bad_json, "invalid JSON");
    expect_client_error("[1,2]", ErrorCode::bad_json, "must be a JSON object");
    expect_client_error("\"ping\"", ErrorCode::bad_json);
    expect_client_error("{\"v\":1,\"type\":\"ping\"} trailing", ErrorCode::bad_json);
    expect_client_error(std::string(20, '[') + std::string(20, ']'), ErrorCode::bad_json,
                        "nested deeper");
    // Brackets inside strings do not count as nesting.
    auto parsed =
        parse_client_message(request("ping", cat({R"("id":")", std::string(40, '['), "\""})));
    EXPECT_TRUE(parsed);
}

TEST(Messages, version_and_type_errors) {
    expect_client_error(R"({"type":"ping"})", ErrorCode::bad_field, "missing field v");
    expect_client_error(R"({"v":3,"type":"ping"})", ErrorCode::unsupported_version, "version 3");
    expect_client_error(R"({"v":"1","type":"ping"})", ErrorCode::bad_field, "field v");
    expect_client_error(R"({"v":1})", ErrorCode::bad_field, "missing field type");
    expect_client_error(R"({"v":1,"type":"explode"})", ErrorCode::unknown_type, "explode");
    expect_client_error(R"({"v":1,"type":7})", ErrorCode::bad_field, "field type");
    // A server message sent by a client is not a request.
    expect_client_error(R"({"v":1,"type":"pong","time_us":1})", ErrorCode::unknown_type);
}

TEST(Messages, request_id_is_returned_with_errors) {
    const RequestError error = client_error(R"({"v":1,"type":"subscribe","id":"abc"})");
    EXPECT_EQ(error.error.code, ErrorCode::bad_field);
    EXPECT_EQ(error.id, RequestId(std::string("abc")));
    EXPECT_EQ(to_reply(error).id, error.id);
    EXPECT_EQ(client_error(R"({"v":9,"type":"ping","id":5})").id, RequestId(std::int64_t{5}));
    expect_client_error(request("ping", R"("id":1.5)"), ErrorCode::bad_field, "field id");
    expect_client_error(request("ping", R"("id":9007199254740992)"), ErrorCode::bad_field);
    expect_client_error(request("ping", R"("id":{})"), ErrorCode::bad_field);
    expect_client_error(request("ping", cat({R"("id":")", std::string(65, 'x'), "\""})),
                        ErrorCode::bad_field);
}

TEST(Messages, errors_of_unparsed_messages_echo_the_id_a_scan_finds) {
    // Nested too deeply: never parsed, but the id is read from the text.
    std::string deep = R"({"v":1,"type":"ping","id":"deep-1","x":)";
    for (int i = 0; i < 40; ++i) deep += "[";
    for (int i = 0; i < 40; ++i) deep += "]";
    deep += "}";
    const RequestError nested = client_error(deep);
    EXPECT_EQ(nested.error.code, ErrorCode::bad_json);
    EXPECT_EQ(nested.id, RequestId(std::string("deep-1")));
    // Too large, with the id after the bulk.
    ParseLimits limits;
    limits.max_message_bytes = 100;
    const std::string big =
        cat({R"({"v":1,"type":"ping","pad":")", std::string(200, 'x'), R"(","id":17})"});
    const RequestError large = client_error(big, limits);
    EXPECT_EQ(large.error.code, ErrorCode::too_large);
    EXPECT_EQ(large.id, RequestId(std::int64_t{17}));
    // Not JSON at all after the id.
    EXPECT_EQ(client_error(R"({"id": -3, "v":1, "type": )").id, RequestId(std::int64_t{-3}));
}

TEST(RequestIdScanner, finds_the_top_level_id_in_pieces_of_any_size) {
    const std::string text =
        R"({"x":{"id":1},"ids":[{"id":2}],"s":"\"id\":3","id":"a\"b\u00e9","id":9})";
    for (std::size_t piece : {1u, 2u, 3u, 7u, 1000u}) {
        RequestIdScanner scanner;
        for (std::size_t i = 0; i < text.size(); i += piece)
            scanner.feed(std::string_view(text).substr(i, piece));
        EXPECT_EQ(scanner.id(), RequestId(std::string("a\"b\u00e9"))) << piece;
    }
    EXPECT_FALSE(scan_request_id(R"({"id":1.5})"));
    EXPECT_FALSE(scan_request_id(R"({"id":{"a":1}})"));
    EXPECT_FALSE(scan_request_id(cat({R"({"id":")", std::string(65, 'y'), "\"}"})));
    EXPECT_EQ(scan_request_id(R"({ "id" : 42 })"), RequestId(std::int64_t{42}));
    EXPECT_FALSE(scan_request_id("[1,2,3]"));
}

TEST(Messages, string_limits_count_characters) {
    std::string id;
    for (int i = 0; i < 64; ++i) id += "\u00e9";  // 64 characters, 128 bytes
    EXPECT_TRUE(parse_client_message(request("ping", cat({R"("id":")", id, "\""}))));
    EXPECT_FALSE(parse_client_message(request("ping", cat({R"("id":")", id, "e\""}))));
    std::string name;
    for (int i = 0; i < 64; ++i) name += "\u03b1";  // 64 Greek alphas
    EXPECT_TRUE(parse_client_message(request(
        "create",
        cat({R"("expression":"x","box":[0,1,0,1,0,1],"parameters":{")", name, R"(":1})"}))));
    EXPECT_EQ(utf8_characters("a\u00e9\U0001F600"), 3u);
}

TEST(Messages, unknown_fields_are_rejected_in_requests) {
    expect_client_error(request("ping", R"("extra":1)"), ErrorCode::bad_field,
                        "unknown field extra");
    expect_client_error(
        request("create", R"("expression":"x","box":[0,1,0,1,0,1],"constraints":{"triangle":5})"),
        ErrorCode::bad_field, "unknown field constraints.triangle");
}

TEST(Messages, session_field_errors) {
    expect_client_error(request("subscribe"), ErrorCode::bad_field, "missing field session");
    expect_client_error(request("pause", R"("session":"xyz")"), ErrorCode::bad_field,
                        "32 hex digits");
    expect_client_error(request("resume", R"("session":12)"), ErrorCode::bad_field,
                        "must be a string");
}

TEST(Messages, create_field_errors) {
    const std::string box = R"("box":[-1,1,-1,1,-1,1])";
    expect_client_error(request("create", box), ErrorCode::bad_field, "missing field expression");
    expect_client_error(request("create", R"("expression":"x")"), ErrorCode::bad_field,
                        "missing field box");
    expect_client_error(request("create", cat({R"("expression":"x","vm":"y",)", box})),
                        ErrorCode::bad_field, "exclusive");
    expect_client_error(request("create", R"("expression":"x","box":[1,0,0,1,0,1])"),
                        ErrorCode::bad_field, "x0 < x1");
    expect_client_error(request("create", R"("expression":"x","box":[0,1,0,1,0])"),
                        ErrorCode::bad_field, "6 numbers");
    expect_client_error(request("create", R"("expression":"x","box":[0,1,0,1,0,"1"])"),
                        ErrorCode::bad_field, "finite numbers");
    expect_client_error(request("create", R"("expression":"x","box":[0,1,0,1,0,1e999])"),
                        ErrorCode::bad_json, "out of range");
    expect_client_error(request("create", cat({R"("expression":7,)", box})), ErrorCode::bad_field,
                        "field expression must be a string");
    expect_client_error(
        request("create", cat({R"("expression":"x","parameters":{"a":"1"},)", box})),
        ErrorCode::bad_field, "parameters.a");
    expect_client_error(request("create", cat({R"("expression":"x","parameters":[1],)", box})),
                        ErrorCode::bad_field, "must be an object");
    expect_client_error(request("create", cat({R"("expression":"x","parameters":{"":1},)", box})),
                        ErrorCode::bad_field, "names");
    expect_client_error(
        request("create", cat({R"("expression":"x","constraints":{"triangles":0},)", box})),
        ErrorCode::bad_field, "constraints.triangles");
    expect_client_error(
        request("create", cat({R"("expression":"x","constraints":{"triangles":1.5},)", box})),
        ErrorCode::bad_field, "must be an integer");
    expect_client_error(
        request("create", cat({R"("expression":"x","constraints":{"max_error":-1},)", box})),
        ErrorCode::bad_field, "constraints.max_error");
    expect_client_error(
        request("create",
                cat({R"("expression":"x","constraints":{"error_measure":"Bad Name"},)", box})),
        ErrorCode::bad_field, "constraints.error_measure");
}

TEST(Messages, update_needs_a_change) {
    expect_client_error(request("update", with_session()), ErrorCode::bad_field, "at least one");
    auto parsed = parse_client_message(request("update", with_session(R"("box":[0,1,0,1,0,1])")));
    ASSERT_TRUE(parsed);
    EXPECT_TRUE(std::get<Update>(parsed.value()).box);
}

TEST(Messages, size_limits_give_too_large) {
    ParseLimits limits;
    limits.max_message_bytes = 100;
    const std::string big = request("ping", cat({R"("id":")", std::string(90, 'x'), "\""}));
    EXPECT_EQ(client_error(big, limits).error.code, ErrorCode::too_large);

    limits = ParseLimits{};
    limits.max_expression_bytes = 8;
    EXPECT_EQ(client_error(request("create", R"("expression":"x+y+z+x+y+z=1","box":[0,1,0,1,0,1])"),
                           limits)
                  .error.code,
              ErrorCode::too_large);

    limits = ParseLimits{};
    limits.max_parameters = 2;
    EXPECT_EQ(client_error(request("create", R"("expression":"x","parameters":{"a":1,"b":2,"c":3},)"
                                             R"("box":[0,1,0,1,0,1])"),
                           limits)
                  .error.code,
              ErrorCode::too_large);
}

TEST(Messages, server_parse_ignores_unknown_fields_and_checks_known_ones) {
    auto parsed = parse_server_message(R"({"v":1,"type":"pong","time_us":5,"new_field":[1]})");
    ASSERT_TRUE(parsed);
    EXPECT_EQ(std::get<Pong>(parsed.value()).time_us, 5u);

    auto missing =
        parse_server_message(cat({R"({"v":1,"type":"progress","session":")", kHex, "\"}"}));
    ASSERT_FALSE(missing);
    EXPECT_EQ(missing.error().code, ErrorCode::bad_field);

    auto bad_ack = parse_server_message(
        cat({R"({"v":1,"type":"ack","request":"create","session":")", kHex, "\"}"}));
    ASSERT_FALSE(bad_ack);
    EXPECT_NE(bad_ack.error().message.find("request"), std::string::npos);

    auto unknown_code =
        parse_server_message(R"({"v":1,"type":"error","code":"from_the_future","message":"m"})");
    ASSERT_TRUE(unknown_code);
    EXPECT_EQ(std::get<ErrorReply>(unknown_code.value()).code, ErrorCode::internal);

    auto client_type = parse_server_message(request("ping"));
    ASSERT_FALSE(client_type);
    EXPECT_EQ(client_type.error().code, ErrorCode::unknown_type);
}

TEST(Messages, message_type_names_round_trip) {
    for (int i = 0; i <= static_cast<int>(MessageType::closed); ++i) {
        const auto type = static_cast<MessageType>(i);
        EXPECT_EQ(message_type_from_string(to_string(type)), type);
    }
}

}  // namespace
}  // namespace isomesh::protocol
