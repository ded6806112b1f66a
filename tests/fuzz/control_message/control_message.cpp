// libFuzzer target: control-message parsing (protocol/messages.h). Any input must give an error or
// a message that serializes to JSON which parses back to the same message.
#include <cstdint>
#include <cstdlib>
#include <string_view>

#include "protocol/messages.h"

using namespace isomesh::protocol;

namespace {

// Serializing may lengthen a message (1e5 is written 100000.0): re-parse with room to spare.
ParseLimits roomy() {
    ParseLimits limits;
    limits.max_message_bytes *= 8;
    limits.max_expression_bytes *= 8;
    limits.max_vm_bytes *= 8;
    return limits;
}

template <class Message, class Parse>
void expect_round_trip(const Message& message, Parse parse) {
    auto again = parse(serialize(message), roomy());
    if (!again || !(again.value() == message)) std::abort();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const std::string_view text(reinterpret_cast<const char*>(data), size);
    if (auto request = parse_client_message(text)) {
        expect_round_trip(request.value(), [](std::string_view t, const ParseLimits& l) {
            return parse_client_message(t, l);
        });
    } else {
        serialize(ServerMessage(to_reply(request.error())));
    }
    if (auto reply = parse_server_message(text)) {
        expect_round_trip(reply.value(), [](std::string_view t, const ParseLimits& l) {
            return parse_server_message(t, l);
        });
    }
    return 0;
}
