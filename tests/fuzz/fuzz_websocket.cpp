// Harness: the live view server's parsing of what a client sends (io/websocket.hpp): the HTTP
// request head and RFC 6455 opening handshake (parse_request), then masked client frames
// (parse_client_frame), as Server reads them from a socket.
//
// Input: byte 0 picks the mode and byte 1 the frame size limit (max_payload_bytes = 0, 125,
// 126, 8192 (the server's default request_max_bytes) or 65536 by byte 1 % 5).
//   - mode even: a client's byte stream. The head is everything before the first "\r\n\r\n"
//     (none: the server waits for more, nothing parsed); after a 101 the rest is frames.
//   - mode odd: the rest is frames (an upgraded connection).
// Oracles:
//   - request: the status is one of the documented codes (101, 200, 400, 404, 405, 426) and
//     agrees with the request line read independently here: 405 exactly for a well-formed line
//     whose method is not GET; 101, 200, 404 and 426 only for GET; 101 only for the endpoint, with
//     a key of 22 base64 characters and "==" that occurs in the head, 200 only for / or
//     /index.html;
//   - frames: kIncomplete consumes nothing and a longer input would be needed (the frame's
//     header or its payload is cut); kError is 1002 or 1009; a frame consumes at most the input,
//     its payload is at most max_payload_bytes (125 for control frames), equals the input's
//     masked payload XOR the mask (checked independently), and its opcode is one the server
//     knows. Frames are parsed front to back as the server does until one is not kFrame.

#include <cstring>
#include <span>
#include <string>
#include <string_view>

#include "io/websocket.hpp"
#include "tests/fuzz/fuzz_input.hpp"
#include "tests/fuzz/harnesses.hpp"

namespace radar_emu::fuzz {

namespace {

namespace ws = radar_emu::io::ws;

constexpr std::string_view kWsPath = "/ws";

bool base64_char(char c) {
  return (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '+' ||
         c == '/';
}

void check_request(std::string_view head, const ws::Request& r) {
  const int status = ws::http_status(r.kind);
  FUZZ_CHECK(status == 101 || status == 200 || status == 400 || status == 404 || status == 405 ||
             status == 426);
  // The request line, read here independently: up to the first CRLF, METHOD SP TARGET SP
  // HTTP/1.x with TARGET free of spaces... or anything else (400).
  const std::string_view line = head.substr(0, head.find("\r\n"));
  const std::size_t sp1 = line.find(' ');
  const bool well_formed = sp1 != std::string_view::npos &&
                           line.find(' ', sp1 + 1) != std::string_view::npos &&
                           line.substr(line.find(' ', sp1 + 1) + 1).starts_with("HTTP/1.");
  const bool get = well_formed && line.substr(0, sp1) == "GET";
  if (!well_formed)
    FUZZ_CHECK(r.kind == ws::Request::Kind::kMalformed);
  if (well_formed)
    FUZZ_CHECK(r.kind != ws::Request::Kind::kMalformed);
  FUZZ_CHECK((r.kind == ws::Request::Kind::kMethodNotAllowed) == (well_formed && !get));
  if (status == 101 || status == 200 || status == 404 || status == 426)
    FUZZ_CHECK(get);
  if (get) {
    std::string_view path = line.substr(4);
    path = path.substr(0, path.find(' '));
    path = path.substr(0, path.find('?'));
    if (r.kind == ws::Request::Kind::kWebSocket || r.kind == ws::Request::Kind::kWrongVersion ||
        r.kind == ws::Request::Kind::kBadHandshake)
      FUZZ_CHECK(path == kWsPath);
    if (r.kind == ws::Request::Kind::kPage)
      FUZZ_CHECK(path == "/" || path == "/index.html");
    if (r.kind == ws::Request::Kind::kNotFound)
      FUZZ_CHECK(path != kWsPath && path != "/" && path != "/index.html");
  }
  if (r.kind == ws::Request::Kind::kWebSocket) {
    FUZZ_CHECK(r.key.size() == 24 && r.key.ends_with("=="));
    for (std::size_t i = 0; i < 22; ++i)
      FUZZ_CHECK(base64_char(r.key[i]));
    FUZZ_CHECK(head.find(r.key) != std::string_view::npos);
    FUZZ_CHECK(ws::accept_key(r.key).size() == 28);  // base64 of 20 bytes
  } else {
    FUZZ_CHECK(r.key.empty());
  }
}

void check_frames(std::span<const std::uint8_t> in, std::size_t max_payload) {
  std::string payload;
  while (true) {
    const ws::ClientFrame f = ws::parse_client_frame(in, max_payload, payload);
    if (f.status == ws::ClientFrame::Status::kError) {
      FUZZ_CHECK(f.close_code == 1002 || f.close_code == 1009);
      FUZZ_CHECK(in.size() >= 2);
      return;
    }
    // The header read independently (RFC 6455 sec. 5.2).
    std::size_t hdr = 2;
    std::uint64_t len = in.size() >= 2 ? (in[1] & 0x7fu) : 0;
    if (len == 126)
      hdr = 4;
    else if (len == 127)
      hdr = 10;
    if (f.status == ws::ClientFrame::Status::kIncomplete) {
      FUZZ_CHECK(f.size == 0);
      if (in.size() >= hdr) {
        // The header is whole: then the frame is masked, not too big, and its payload cut.
        FUZZ_CHECK((in[1] & 0x80u) != 0);
        len = 0;
        if (hdr == 2)
          len = in[1] & 0x7fu;
        for (std::size_t i = 2; i < hdr; ++i)
          len = len << 8 | in[i];
        FUZZ_CHECK(len <= max_payload);
        FUZZ_CHECK(in.size() < hdr + 4 + len);
      }
      return;
    }
    FUZZ_CHECK(f.status == ws::ClientFrame::Status::kFrame);
    FUZZ_CHECK(f.size <= in.size());
    FUZZ_CHECK(payload.size() <= max_payload);
    FUZZ_CHECK(f.size == hdr + 4 + payload.size());
    FUZZ_CHECK((in[1] & 0x80u) != 0);
    FUZZ_CHECK(f.opcode <= 0x2 || f.opcode == 0x8 || f.opcode == 0x9 || f.opcode == 0xA);
    FUZZ_CHECK(f.opcode == (in[0] & 0x0fu));
    if ((f.opcode & 0x8u) != 0)
      FUZZ_CHECK(payload.size() <= 125);
    const std::uint8_t* mask = in.data() + hdr;
    for (std::size_t i = 0; i < payload.size(); ++i)
      FUZZ_CHECK(static_cast<std::uint8_t>(payload[i]) ==
                 static_cast<std::uint8_t>(in[hdr + 4 + i] ^ mask[i % 4]));
    if (f.opcode == 0x8)
      return;  // the server answers close and stops reading
    in = in.subspan(f.size);
  }
}

}  // namespace

int websocket(const std::uint8_t* data, std::size_t size) {
  FuzzInput input(data, size);
  const std::uint8_t mode = input.u8();
  static constexpr std::size_t kLimits[] = {0, 125, 126, 8192, 65536};
  const std::size_t max_payload = kLimits[input.u8() % 5];
  const std::span<const std::uint8_t> rest = input.rest();
  if ((mode & 1u) != 0) {
    check_frames(rest, max_payload);
    return 0;
  }
  const std::string_view stream(reinterpret_cast<const char*>(rest.data()), rest.size());
  const std::size_t end = stream.find("\r\n\r\n");
  if (end == std::string_view::npos)
    return 0;
  const std::string_view head = stream.substr(0, end);
  const ws::Request r = ws::parse_request(head, kWsPath);
  check_request(head, r);
  if (r.kind == ws::Request::Kind::kWebSocket)
    check_frames(rest.subspan(end + 4), max_payload);
  return 0;
}

}  // namespace radar_emu::fuzz
