// libFuzzer target: the indexer's reply parser. Any bytes as what the serial
// line delivered: framing, position and status parsing are total, and a
// position they accept reads back from its own formatting.
#include <cstdint>
#include <cstdlib>
#include <string>

#include "rig/hardware/indexer.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string bytes(reinterpret_cast<const char*>(data), size);
  const rig::IndexerDialect& d = rig::IndexerDialect::Compumotor6k();
  // Every prefix, as the bytes arrive in pieces.
  for (size_t n = 0; n <= bytes.size(); n += 1 + n / 8) {
    const rig::IndexerDialect::Reply r = d.ParseReply(bytes.substr(0, n));
    if (r.status == rig::IndexerDialect::Reply::kIncomplete && !r.text.empty()) std::abort();
  }
  for (const std::string& reply : {bytes, d.position_reply + bytes, d.status_reply + bytes}) {
    if (const auto steps = d.ParsePosition(reply)) {
      const std::string again =
          d.position_reply + (*steps >= 0 ? "+" : "") + std::to_string(*steps);
      if (d.ParsePosition(again) != steps) std::abort();
    }
    if (const auto bits = d.ParseStatus(reply))
      if (bits->size() != 32 || bits->find_first_not_of("01") != std::string::npos) std::abort();
  }
  return 0;
}
