// Finds the top-level "id" of a request that cannot be parsed, fed in pieces of any size.
#pragma once

#include <optional>
#include <string>
#include <string_view>

#include "protocol/messages.h"

namespace isomesh::protocol {

/// Finds the top-level "id" of a request that cannot be parsed (too large, nested too deeply,
/// malformed), fed in pieces of any size: a tolerant scan in constant memory, so that even the
/// error about a message too large to keep echoes its id. The id is the first top-level "id"
/// key's value when it is a valid request id.
class RequestIdScanner {
  public:
    void feed(std::string_view text);
    std::optional<RequestId> id() const;

  private:
    enum class Phase { before_key, in_key, after_key, before_value, in_value, after_value };
    void top_level(char c);
    void capture(char c);
    int depth_ = 0;
    bool in_string_ = false;
    bool escaped_ = false;
    Phase phase_ = Phase::before_key;
    std::string key_;
    std::string value_;
    bool key_is_id_ = false;
    bool value_is_string_ = false;
    bool done_ = false;  // the id's value is complete, or cannot be one
};

/// RequestIdScanner over a whole text.
std::optional<RequestId> scan_request_id(std::string_view text);

}  // namespace isomesh::protocol
