#pragma once
// Every message of docs/protocol.md as a C++ value. The envelope is the same for all of them:
// {v: protocol version, type: name, seq: sequence number, token: run token, body: map}.
#include <cstdint>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include "sphfsi/protocol/solver.hpp"

namespace sphfsi::protocol {

// The version this build speaks, and the oldest it still accepts. Bump kProtocolVersion on any change
// to a message's fields or meaning; see section 3.1, "Version negotiation", in docs/protocol.md.
inline constexpr std::uint32_t kProtocolVersion = 2;
inline constexpr std::uint32_t kOldestSupportedVersion = 1;

enum class MessageType {
    Hello, Welcome, Init, Ready, Advance, Advanced, Save, Restore, Snapshot, Frame,
    Checkpoint, State, Ack, Heartbeat, Bye, Error,
};
std::string_view to_string(MessageType t);
bool parse_message_type(std::string_view name, MessageType& out);
// HEARTBEAT and ERROR are not requests: they are never answered, malformed or not, whatever their token
// (docs/protocol.md, "Errors"); answering an ERROR could start a ping-pong of ERRORs.
inline bool is_answered(MessageType t) { return t != MessageType::Heartbeat && t != MessageType::Error; }
// The reply each request expects besides ERROR (docs/protocol.md §3-4); HEARTBEAT for anything that is not
// a request.
inline MessageType expected_reply(MessageType request) {
    switch (request) {
        case MessageType::Hello: return MessageType::Welcome;
        case MessageType::Init: return MessageType::Ready;
        case MessageType::Advance: return MessageType::Advanced;
        case MessageType::Snapshot: return MessageType::Frame;
        case MessageType::Checkpoint: return MessageType::State;
        case MessageType::Save:
        case MessageType::Restore:
        case MessageType::Bye: return MessageType::Ack;
        default: return MessageType::Heartbeat;
    }
}

struct Hello {                       // participant -> coordinator, first message
    std::string name;                // role in the scene: "fluid" or "structure"
    std::string kind;                // what it is: "fluid" or "structure"
    std::uint32_t version_min = 0;   // oldest protocol version it speaks
    std::uint32_t version_max = 0;   // newest protocol version it speaks
    std::string software;            // free text, e.g. "sphfsi-structure 0.1.0"
    std::int64_t pid = 0;            // its process id (0 if not meaningful)
    bool operator==(const Hello&) const = default;
};

struct Welcome {                     // coordinator -> participant, answer to HELLO
    std::uint32_t version = 0;       // the protocol version both sides now use
    double heartbeat_s = 0.0;        // send a HEARTBEAT at least this often
    double timeout_s = 0.0;          // a peer silent this long is declared dead
    bool operator==(const Welcome&) const = default;
};

struct Frame {                       // participant -> coordinator, answer to SNAPSHOT
    double t = 0.0;
    Fields fields;
};

struct State {                       // participant -> coordinator, answer to CHECKPOINT
    double t = 0.0;
    std::vector<std::uint8_t> bytes;  // opaque; handed back in INIT.state to resume
};

struct Heartbeat {                   // both directions, any time after WELCOME
    std::uint64_t progress = 0;      // steps completed so far (participant); 0 from the coordinator
    bool operator==(const Heartbeat&) const = default;
};

struct ErrorReply {                  // either direction
    std::string code;                // see the table in docs/protocol.md
    std::string message;             // one human sentence
    std::uint64_t in_reply_to = 0;   // seq of the offending message, 0 if unknown
    bool operator==(const ErrorReply&) const = default;
};

struct Empty {                       // SAVE, RESTORE, SNAPSHOT, CHECKPOINT, ACK, BYE
    bool operator==(const Empty&) const = default;
};

using Body = std::variant<Empty, Hello, Welcome, InitRequest, InitReply, AdvanceRequest, AdvanceReply,
                          Frame, State, Heartbeat, ErrorReply>;

struct Message {
    std::uint32_t version = kProtocolVersion;
    MessageType type = MessageType::Ack;
    std::uint64_t seq = 0;
    std::string token;
    Body body;

    template <class T>
    const T& as() const;  // throws ProtocolError if the body is not a T
};

// A message that breaks the protocol ("bad_message", "too_large", "unknown_type", "version_mismatch").
class ProtocolError : public CodedError {
public:
    using CodedError::CodedError;
    ProtocolError(std::string code, const std::string& message, std::uint64_t seq, std::string type_name)
        : CodedError(std::move(code), message), seq_(seq), type_name_(std::move(type_name)) {}
    // The offending message's envelope seq where it could be read, else 0: the ERROR answering it carries
    // it as seq and in_reply_to (docs/protocol.md, "Envelope").
    std::uint64_t seq() const { return seq_; }
    // Its envelope type as written, where it could be read, else empty: a malformed HEARTBEAT or ERROR is
    // not answered (docs/protocol.md, "Errors").
    const std::string& type_name() const { return type_name_; }
    bool answerable() const {
        MessageType t;
        return !parse_message_type(type_name_, t) || is_answered(t);
    }

private:
    std::uint64_t seq_ = 0;
    std::string type_name_;
};

template <class T>
const T& Message::as() const {
    if (const T* b = std::get_if<T>(&body)) return *b;
    throw ProtocolError("bad_message", std::string(to_string(type)) + " does not carry the expected body");
}

// Builds a message of `type` whose body kind is implied by the type.
Message make_message(MessageType type, std::uint64_t seq, std::string token, Body body = Empty{});

}  // namespace sphfsi::protocol
