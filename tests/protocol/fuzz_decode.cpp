// libFuzzer target: the decoder must refuse anything malformed with a ProtocolError, never crash.
#include <cstddef>
#include <cstdint>

#include "sphfsi/protocol/codec.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    try {
        sphfsi::protocol::Message m = sphfsi::protocol::decode(data, size);
        (void)sphfsi::protocol::encode(m);  // whatever decodes must encode again
    } catch (const sphfsi::protocol::ProtocolError&) {
    }
    return 0;
}
