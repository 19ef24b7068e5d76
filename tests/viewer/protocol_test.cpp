// The viewer's wire format (docs/viewer.md): every field of a frame at its
// documented offset, and every malformed command refused with its reason.
#include "protocol.hpp"

#include <gtest/gtest.h>

#include <cstring>

namespace pdyn::viewer {
namespace {

template <class T>
T at(const std::string& bytes, std::size_t offset) {
  T v;
  std::memcpy(&v, bytes.data() + offset, sizeof v);
  return v;
}

Frame two_particle_frame() {
  Frame f;
  f.topology = 7;
  f.time = 1.25;
  f.step = 1ull << 40;
  f.playing = true;
  f.kinetic = 3.5;
  f.potential = -2.0;
  f.positions = {1, 2, 3, -4, 5.5f, 6};
  f.speeds = {0.5f, 9};
  return f;
}

TEST(ViewerFrame, FieldsSitAtTheDocumentedOffsets) {
  const std::string b = encode_frame(two_particle_frame());
  ASSERT_EQ(b.size(), 48u + 12u * 2 + 4u * 2);
  EXPECT_EQ(b.substr(0, 4), "PDYF");
  EXPECT_EQ(at<std::uint32_t>(b, 4), 7u);
  EXPECT_EQ(at<double>(b, 8), 1.25);
  EXPECT_EQ(at<std::uint64_t>(b, 16), 1ull << 40);
  EXPECT_EQ(at<std::uint32_t>(b, 24), 2u);
  EXPECT_EQ(at<std::uint32_t>(b, 28), 1u);
  EXPECT_EQ(at<double>(b, 32), 3.5);
  EXPECT_EQ(at<double>(b, 40), -2.0);
  EXPECT_EQ(at<float>(b, 48 + 4 * 4), 5.5f);   // y of particle 1
  EXPECT_EQ(at<float>(b, 48 + 24 + 4), 9.0f);  // speed of particle 1
}

TEST(ViewerFrame, DecodesWhatItEncodesAndRefusesBrokenFrames) {
  const Frame f = two_particle_frame();
  const std::string b = encode_frame(f);
  const Frame g = decode_frame(b);
  EXPECT_EQ(g.topology, f.topology);
  EXPECT_EQ(g.step, f.step);
  EXPECT_EQ(g.positions, f.positions);
  EXPECT_EQ(g.speeds, f.speeds);
  EXPECT_TRUE(g.playing);
  EXPECT_THROW(decode_frame(b.substr(0, 40)), ProtocolError);
  EXPECT_THROW(decode_frame(b.substr(0, b.size() - 1)), ProtocolError);
  std::string bad = b;
  bad[0] = 'X';
  EXPECT_THROW(decode_frame(bad), ProtocolError);
  EXPECT_EQ(encode_frame(Frame{}).size(), 48u);  // an empty scene is a header
}

TEST(ViewerCommand, EveryOpParsesWithItsFields) {
  using Op = Command::Op;
  EXPECT_EQ(parse_command(R"({"op":"play"})").op, Op::Play);
  EXPECT_EQ(parse_command(R"({"op":"reload"})").op, Op::Reload);
  EXPECT_EQ(*parse_command(R"({"op":"speed","value":2.5})").value, 2.5);
  EXPECT_EQ(parse_command(R"({"op":"solver","name":"rk4"})").name, "rk4");
  const Command d = parse_command(R"({"op":"drag","id":12,"point":[1,2.5,-3],"ks":10})");
  EXPECT_EQ(d.op, Op::Drag);
  EXPECT_EQ(*d.id, 12);
  EXPECT_EQ(*d.point, Vec3(1, 2.5, -3));
  EXPECT_EQ(*d.ks, 10.0);
  EXPECT_FALSE(d.kd);
  const Command a = parse_command(R"({"op":"attach","a":3,"b":4})");
  EXPECT_EQ(*a.a, 3);
  EXPECT_EQ(*a.b, 4);
  const Command c = parse_command(R"({"op":"create","point":[0,0,1],"mass":0.5})");
  EXPECT_EQ(*c.mass, 0.5);
}

std::string protocol_refusal(const std::string& text) {
  try {
    parse_command(text);
  } catch (const ProtocolError& e) {
    return e.what();
  }
  return "accepted";
}

TEST(ViewerCommand, EachMalformedMessageGetsItsReason) {
  // The JSON library's own detail follows the prefix; the expectation ends it.
  const std::string not_json = protocol_refusal("{op: play");
  EXPECT_EQ(not_json.rfind("message is not JSON: ", 0), 0u) << not_json;
  EXPECT_NE(not_json.find("(expected a JSON object with an 'op')"), std::string::npos);
  EXPECT_EQ(protocol_refusal("[1,2]"),
            "message is a JSON array (expected a JSON object with an 'op')");
  EXPECT_EQ(protocol_refusal(R"({"id":3})")
                .rfind("message has no 'op' string (expected one of: play, ", 0),
            0u);
  EXPECT_EQ(protocol_refusal(R"({"op":"explode"})")
                .rfind("unknown op 'explode' (expected one of: play,", 0),
            0u);
  EXPECT_EQ(protocol_refusal(R"({"op":"nail"})"),
            "nail: field 'id' is missing (expected a particle index, an integer >= 0)");
  EXPECT_EQ(protocol_refusal(R"({"op":"nail","id":-1})"),
            "nail: field 'id' is -1 (expected a particle index, an integer >= 0)");
  EXPECT_EQ(protocol_refusal(R"({"op":"nail","id":1.5})"),
            "nail: field 'id' is 1.5 (expected a particle index, an integer >= 0)");
  EXPECT_EQ(protocol_refusal(R"({"op":"move","point":[1,2]})"),
            "move: field 'point' is [1,2] (expected [x, y, z], three finite numbers in m)");
  EXPECT_EQ(protocol_refusal(R"({"op":"move","point":[1,"a",2]})"),
            "move: field 'point' is [1,\"a\",2] (expected [x, y, z], three finite numbers in m)");
  EXPECT_EQ(protocol_refusal(R"({"op":"dt","value":0})"),
            "dt: field 'value' is 0 (expected a number > 0)");
  EXPECT_EQ(protocol_refusal(R"({"op":"speed","value":"fast"})"),
            "speed: field 'value' is string (expected a number)");
  EXPECT_EQ(protocol_refusal(R"({"op":"create","point":[0,0,0],"mass":-1})"),
            "create: field 'mass' is -1 (expected a number > 0)");
  EXPECT_EQ(protocol_refusal(R"({"op":"attach","a":1,"b":2,"ks":-5})"),
            "attach: field 'ks' is -5 (expected a number >= 0)");
  EXPECT_EQ(protocol_refusal(R"({"op":"solver","name":7})"),
            "solver: field 'name' is missing or not a string (expected a solver name)");
  const std::string huge = R"({"op":"play","pad":")" + std::string(70000, 'x') + "\"}";
  EXPECT_EQ(protocol_refusal(huge), "message of " + std::to_string(huge.size()) +
                                        " bytes is too long (expected at most 65536 bytes)");
}

TEST(ViewerCommand, RepliesAreJsonWithTheirOp) {
  EXPECT_EQ(ack_message("create", 5), R"({"id":5,"op":"create","type":"ack"})");
  EXPECT_EQ(error_message("", "bad"), R"({"message":"bad","op":null,"type":"error"})");
  // A client's invalid UTF-8 echoed in a message does not throw.
  EXPECT_NO_THROW(error_message("x", std::string("\xff\xfe", 2)));
}

}  // namespace
}  // namespace pdyn::viewer
