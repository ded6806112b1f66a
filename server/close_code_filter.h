// The close codes a WebSocket peer may send (RFC 6455, 7.4), enforced on the bytes a client sends
// before Boost.Beast reads them: Beast 1.74 accepts close codes of 5000 and above, which RFC 6455
// leaves undefined, and echoes them back. This filter follows the client-to-server frames
// (RFC 6455, 5.2: header, optional extended length, mask key, payload) across reads of any size
// and rewrites an invalid code in a close frame, in place, to 1005: a reserved code that Beast
// refuses like every other invalid one, failing the connection with close code 1002 (protocol
// error) instead of echoing. The code's two bytes must be rewritten together, so a read that ends
// between them releases all but its last byte, which the reader keeps for the next read.
#pragma once

#include <array>
#include <cstdint>
#include <span>

namespace isomesh::server {

/// True for the close codes an endpoint may send: 1000-1003, 1007-1014, 3000-4999.
bool valid_close_code(std::uint16_t code);

class CloseCodeFilter {
  public:
    /// Inspects the next bytes of the stream, rewriting an invalid close code, and returns how
    /// many of them may be passed on: all, or all but the last when it is the first byte of a
    /// close code (the caller keeps it and passes it again first with the next bytes).
    std::size_t filter(std::span<std::uint8_t> bytes);

  private:
    enum class State { opcode, length, extended_length, mask, payload };
    void header_byte(std::uint8_t byte);
    void code(std::uint8_t& high, std::uint8_t& low);
    void start_payload();

    State state_ = State::opcode;
    bool close_ = false;  // the frame being read is a close frame
    bool masked_ = false;
    int length_bytes_ = 0;  // extended length bytes still to read
    int mask_bytes_ = 0;    // mask key bytes read
    std::uint64_t length_ = 0;
    std::uint64_t offset_ = 0;  // payload bytes read
    std::array<std::uint8_t, 4> key_{};
};

}  // namespace isomesh::server
