// The session's CURVE keys: what is read, and every malformed key refused with an error naming
// it (a key of the wrong length or alphabet, a key for no input, an input without a key, a secret
// key file others can read).
#include "curve_keys.h"

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <zmq.h>

#include <fstream>
#include <nlohmann/json.hpp>

#include "curve_test_keys.h"

namespace mocap {
namespace {

using nlohmann::json;

using testing::KeyPair;

// Writes text to name in the test folder with the given mode; its path.
std::string WriteKey(const std::string& name, const std::string& text, mode_t mode) {
  const std::string path = ::testing::TempDir() + "/" + name;
  std::remove(path.c_str());
  std::ofstream(path) << text;
  chmod(path.c_str(), mode);
  return path;
}

TEST(CurveKeys, AKeyIsFortyCharactersOfZ85) {
  const KeyPair k;
  EXPECT_TRUE(IsCurveKey(k.pub));
  EXPECT_TRUE(IsCurveKey(k.secret));
  EXPECT_FALSE(IsCurveKey(""));
  EXPECT_FALSE(IsCurveKey(k.pub.substr(1)));
  EXPECT_FALSE(IsCurveKey(k.pub + "a"));
  EXPECT_FALSE(IsCurveKey("\"" + k.pub.substr(1)));  // '"' is not in Z85's alphabet
  EXPECT_FALSE(IsCurveKey(std::string(40, ' ')));
}

TEST(CurveKeys, TheSecretKeyFileGivesBothKeysAndMustBeTheOwnersOnly) {
  const KeyPair k;
  std::string pub, secret, error;
  ASSERT_TRUE(ReadSecretKeyFile(WriteKey("host.key", k.secret + "\n", 0600), &pub, &secret, &error))
      << error;
  EXPECT_EQ(pub, k.pub);
  EXPECT_EQ(secret, k.secret);
  EXPECT_FALSE(ReadSecretKeyFile(WriteKey("open.key", k.secret, 0644), &pub, &secret, &error));
  EXPECT_NE(error.find("readable by others (mode 0644): chmod 600"), std::string::npos) << error;
  EXPECT_FALSE(ReadSecretKeyFile(WriteKey("bad.key", "not a key", 0600), &pub, &secret, &error));
  EXPECT_NE(error.find("is not a secret key"), std::string::npos) << error;
  EXPECT_FALSE(ReadSecretKeyFile(::testing::TempDir() + "/none.key", &pub, &secret, &error));
  EXPECT_NE(error.find("cannot open secret key"), std::string::npos) << error;
}

TEST(CurveKeys, TheSessionsKeysAreReadAndEveryMistakeNamed) {
  const KeyPair host, box, client;
  WriteKey("host.key", host.secret, 0600);
  const std::vector<std::string> inputs = {"tcp://box-1:5600", "tcp://box-2:5600"};
  const json good = {{"host_key", "host.key"},
                     {"inputs", {{"tcp://box-1:5600", box.pub}, {"tcp://box-2:5600", box.pub}}},
                     {"subscribers", {client.pub}}};
  CurveKeys keys;
  std::string error;
  ASSERT_TRUE(ReadCurveKeys(good, ::testing::TempDir(), inputs, &keys, &error)) << error;
  EXPECT_EQ(keys.host_public, host.pub);
  EXPECT_EQ(keys.input_keys.at("tcp://box-2:5600"), box.pub);
  EXPECT_EQ(keys.subscribers, std::vector<std::string>{client.pub});
  EXPECT_TRUE(keys.restrict_subscribers);
  const auto with = [&](const std::string& pointer, const json& value) {
    json j = good;
    j[json::json_pointer(pointer)] = value;
    return j;
  };
  json no_box2 = good;
  no_box2["inputs"].erase("tcp://box-2:5600");
  const std::vector<std::pair<json, std::string>> cases = {
      {with("/inputs/tcp:~1~1box-1:5600", box.pub.substr(0, 39)), "key of 'tcp://box-1:5600'"},
      {with("/inputs/tcp:~1~1box-1:5600", 5), "key of 'tcp://box-1:5600'"},
      {with("/inputs/tcp:~1~1box-9:5600", box.pub), "'tcp://box-9:5600', which is not an input"},
      {no_box2, "no key for input 'tcp://box-2:5600'"},
      {with("/subscribers", json::array({"short"})), "subscriber \"short\" is not a public key"},
      {with("/host_key", "none.key"), "cannot open secret key"},
      {with("/server_key", box.pub), "unknown curve key 'server_key'"},
      {json::array(), "curve is an object"},
  };
  for (const auto& [j, message] : cases) {
    EXPECT_FALSE(ReadCurveKeys(j, ::testing::TempDir(), inputs, &keys, &error)) << j.dump();
    EXPECT_NE(error.find(message), std::string::npos) << error;
  }
}

TEST(CurveKeys, LocalEndpointsAreThoseThatStayOnThisMachine) {
  for (const char* e : {"tcp://127.0.0.1:5600", "tcp://127.1.2.3:1", "tcp://localhost:5600",
                        "tcp://[::1]:5600", "ipc:///tmp/x", "inproc://y"})
    EXPECT_TRUE(IsLocalEndpoint(e)) << e;
  for (const char* e : {"tcp://box-1.local:5600", "tcp://*:5700", "tcp://192.168.1.5:5600",
                        "tcp://127.0.0.1.example.org:5600", "tcp://eth0:5600", "udp://127.0.0.1:1"})
    EXPECT_FALSE(IsLocalEndpoint(e)) << e;
}

}  // namespace
}  // namespace mocap
