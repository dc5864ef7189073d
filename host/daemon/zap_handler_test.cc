// mocapd's output with a "subscribers" list: an allowed client reads the poses, another client
// is refused by the ZAP handler (counted) and reads nothing.
#include "zap_handler.h"

#include <gtest/gtest.h>
#include <zmq.h>

#include <zmq_addon.hpp>

#include "curve_test_keys.h"

namespace mocap {
namespace {

using testing::KeyPair;

zmq::socket_t Client(zmq::context_t& context, const std::string& endpoint, const KeyPair& own,
                     const std::string& server) {
  zmq::socket_t sub(context, zmq::socket_type::sub);
  sub.set(zmq::sockopt::linger, 0);
  sub.set(zmq::sockopt::subscribe, "");
  sub.set(zmq::sockopt::curve_serverkey, server);
  sub.set(zmq::sockopt::curve_publickey, own.pub);
  sub.set(zmq::sockopt::curve_secretkey, own.secret);
  sub.connect(endpoint);
  return sub;
}

TEST(ZapHandler, OnlyTheListedSubscribersRead) {
  const KeyPair host, allowed, stranger;
  zmq::context_t context;
  ZapHandler zap(context, {allowed.pub});
  zmq::socket_t pub(context, zmq::socket_type::pub);
  pub.set(zmq::sockopt::linger, 0);
  pub.set(zmq::sockopt::curve_server, true);
  pub.set(zmq::sockopt::curve_secretkey, host.secret);
  pub.bind("tcp://127.0.0.1:*");
  const std::string endpoint = pub.get(zmq::sockopt::last_endpoint);
  zmq::socket_t reader = Client(context, endpoint, allowed, host.pub);
  zmq::socket_t other = Client(context, endpoint, stranger, host.pub);
  int read = 0, read_by_other = 0;
  zmq::message_t m;
  for (int i = 0; i < 1000 && (read < 10 || zap.refused() < 1); ++i) {
    pub.send(zmq::str_buffer("pose"), zmq::send_flags::none);
    zmq::pollitem_t item{zap.socket().handle(), 0, ZMQ_POLLIN, 0};
    zmq::poll(&item, 1, std::chrono::milliseconds(5));
    zap.Handle();
    while (reader.recv(m, zmq::recv_flags::dontwait)) read++;
    while (other.recv(m, zmq::recv_flags::dontwait)) read_by_other++;
  }
  EXPECT_GE(read, 10);
  EXPECT_EQ(read_by_other, 0);
  EXPECT_GE(zap.refused(), 1u);
  EXPECT_GE(zap.accepted(), 1u);
}

}  // namespace
}  // namespace mocap
