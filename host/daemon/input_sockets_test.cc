// mocapd's subscribers with CURVE: a publisher on an input's endpoint that does not hold the
// secret key the session expects there is refused (none of its messages arrives) and counted
// on that input; the right publisher is heard, after a stranger too.
#include "input_sockets.h"

#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>
#include <zmq.h>

#include <functional>
#include <thread>
#include <utility>
#include <vector>

#include "curve_test_keys.h"

namespace mocap {
namespace {

using testing::KeyPair;

// A publisher on endpoint ("...:*" picks a port); secret empty: no CURVE.
zmq::socket_t Publisher(zmq::context_t& context, const std::string& endpoint,
                        const std::string& secret) {
  zmq::socket_t pub(context, zmq::socket_type::pub);
  pub.set(zmq::sockopt::linger, 0);
  if (!secret.empty()) {
    pub.set(zmq::sockopt::curve_server, true);
    pub.set(zmq::sockopt::curve_secretkey, secret);
  }
  // A port closed a moment ago by another socket is released by ZeroMQ's I/O thread shortly.
  for (int attempt = 0;; ++attempt) {
    try {
      pub.bind(endpoint);
      return pub;
    } catch (const zmq::error_t& e) {
      if (e.num() != EADDRINUSE || attempt == 100) throw;
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
  }
}

class SecureInputs : public ::testing::Test {
 protected:
  // Publishes from pub and runs the inputs until done(messages received) or 1000 polls of at
  // most 5 ms; the messages received.
  int Run(zmq::socket_t& pub, const std::function<bool(int)>& done) {
    int received = 0;
    for (int i = 0; i < 1000 && !done(received); ++i) {
      pub.send(zmq::str_buffer("mocap.v1.Health"), zmq::send_flags::sndmore);
      pub.send(zmq::str_buffer(""), zmq::send_flags::none);
      inputs_.Poll(std::chrono::milliseconds(5));
      inputs_.Drain([&](size_t, std::vector<zmq::message_t>&) { received++; });
      // Past the retry delay at once: the test need not wait a second per retry.
      inputs_.Watch(++tick_ * InputSockets::kRetryNs);
    }
    return received;
  }
  // The session expects box_ on the endpoint of a first publisher, bound here.
  zmq::socket_t OpenWith(const std::string& secret) {
    zmq::socket_t pub = Publisher(context_, "tcp://127.0.0.1:*", secret);
    endpoint_ = pub.get(zmq::sockopt::last_endpoint);
    session_.inputs = {endpoint_};
    session_.curve = CurveKeys{host_.pub, host_.secret, {{endpoint_, box_.pub}}, {}, false};
    std::string error;
    EXPECT_TRUE(inputs_.Open(session_, &error)) << error;
    return pub;
  }
  const InputLink& link() const { return inputs_.links().at(0); }

  zmq::context_t context_;
  KeyPair host_, box_, stranger_;
  Session session_;
  std::string endpoint_;
  int64_t tick_ = 0;
  InputSockets inputs_{context_};
};

TEST_F(SecureInputs, AStrangerIsRefusedAndCountedThenTheBoxIsHeard) {
  zmq::socket_t stranger = OpenWith(stranger_.secret);
  EXPECT_EQ(Run(stranger, [&](int) { return link().handshake_failures >= 3; }), 0);
  EXPECT_GE(link().handshake_failures, 3u);
  EXPECT_FALSE(link().connected);
  stranger.close();
  const uint64_t refused = link().handshake_failures;
  zmq::socket_t box = Publisher(context_, endpoint_, box_.secret);
  EXPECT_GE(Run(box, [](int received) { return received >= 10; }), 10);
  EXPECT_TRUE(link().connected);
  EXPECT_EQ(link().handshake_failures, refused);
}

TEST_F(SecureInputs, APublisherWithoutCurveIsRefusedAndTheInputConnectedAnew) {
  zmq::socket_t plain = OpenWith("");
  EXPECT_EQ(Run(plain, [&](int) { return link().handshake_failures >= 2; }), 0);
  // libzmq alone would not retry after this protocol error: the second failure shows the
  // input connected anew.
  EXPECT_GE(link().handshake_failures, 2u);
  plain.close();
  zmq::socket_t box = Publisher(context_, endpoint_, box_.secret);
  EXPECT_GE(Run(box, [](int received) { return received >= 10; }), 10);
}

TEST_F(SecureInputs, HealthReportsEachInputsLink) {
  zmq::socket_t stranger = OpenWith(stranger_.secret);
  Run(stranger, [&](int) { return link().handshake_failures >= 1; });
  v1::Health health;
  inputs_.AppendTo(&health);
  ASSERT_EQ(health.streams_size(), 1);
  EXPECT_EQ(health.streams(0).stream(), "link/" + endpoint_);
  EXPECT_FALSE(health.streams(0).active());
  EXPECT_EQ(health.streams(0).handshake_failures(), link().handshake_failures);
  EXPECT_GE(health.streams(0).handshake_failures(), 1u);
}

TEST(Inputs, WithoutKeysAPlainPublisherIsHeard) {
  zmq::context_t context;
  zmq::socket_t pub = Publisher(context, "tcp://127.0.0.1:*", "");
  Session session;
  session.inputs = {pub.get(zmq::sockopt::last_endpoint)};
  InputSockets inputs(context);
  std::string error;
  ASSERT_TRUE(inputs.Open(session, &error)) << error;
  int received = 0;
  for (int i = 0; i < 1000 && received < 10; ++i) {
    pub.send(zmq::str_buffer("x"), zmq::send_flags::none);
    inputs.Poll(std::chrono::milliseconds(5));
    inputs.Drain([&](size_t, std::vector<zmq::message_t>&) { received++; });
    inputs.Watch(0);
  }
  EXPECT_GE(received, 10);
  EXPECT_EQ(inputs.links().at(0).handshake_failures, 0u);
  EXPECT_TRUE(inputs.links().at(0).connected);
}

// Polls the inputs for up to seconds_max; the messages received and the inputs closed.
std::pair<int, std::vector<size_t>> Listen(InputSockets& inputs, double seconds_max,
                                           const std::function<bool(int, size_t)>& done) {
  int received = 0;
  std::vector<size_t> closed;
  const auto until = std::chrono::steady_clock::now() +
                     std::chrono::milliseconds(static_cast<int64_t>(seconds_max * 1000));
  while (std::chrono::steady_clock::now() < until && !done(received, closed.size())) {
    inputs.Poll(std::chrono::milliseconds(5));
    inputs.Drain([&](size_t, std::vector<zmq::message_t>&) { received++; });
    inputs.Watch(0);
    for (size_t i : inputs.TakeClosed()) closed.push_back(i);
  }
  return {received, closed};
}

// A box that goes away (its process ended, its socket closed) is reported at once, by the
// index its messages came with, so the host stops waiting for its frames.
TEST(Inputs, AClosedPublisherIsReportedByItsInputsIndex) {
  zmq::context_t context;
  zmq::socket_t first = Publisher(context, "tcp://127.0.0.1:*", "");
  zmq::socket_t second = Publisher(context, "tcp://127.0.0.1:*", "");
  Session session;
  session.inputs = {first.get(zmq::sockopt::last_endpoint),
                    second.get(zmq::sockopt::last_endpoint)};
  InputSockets inputs(context);
  std::string error;
  ASSERT_TRUE(inputs.Open(session, &error)) << error;
  std::vector<int> received(2, 0);
  for (int i = 0; i < 1000 && (received[0] < 3 || received[1] < 3); ++i) {
    first.send(zmq::str_buffer("a"), zmq::send_flags::none);
    second.send(zmq::str_buffer("b"), zmq::send_flags::none);
    inputs.Poll(std::chrono::milliseconds(5));
    inputs.Drain([&](size_t input, std::vector<zmq::message_t>& parts) {
      EXPECT_EQ(parts.at(0).to_string(), input == 0 ? "a" : "b");
      received.at(input)++;
    });
    inputs.Watch(0);
  }
  ASSERT_GE(received[1], 3);
  EXPECT_TRUE(inputs.TakeClosed().empty());
  second.close();
  const auto [_, closed] = Listen(inputs, 5, [](int, size_t closed) { return closed > 0; });
  EXPECT_EQ(closed, std::vector<size_t>{1});
  EXPECT_FALSE(inputs.links().at(1).connected);
  EXPECT_TRUE(inputs.links().at(0).connected);
}

// A publisher in a process of its own that sends until it is killed; its endpoint.
pid_t ForkPublisher(std::string* endpoint) {
  int fds[2];
  if (pipe(fds) != 0) return -1;
  const pid_t pid = fork();
  if (pid == 0) {  // the child: a context of its own, never returns
    close(fds[0]);
    zmq::context_t context;
    zmq::socket_t pub = Publisher(context, "tcp://127.0.0.1:*", "");
    const std::string bound = pub.get(zmq::sockopt::last_endpoint);
    if (write(fds[1], bound.data(), bound.size()) < 0) _exit(1);
    close(fds[1]);
    for (;;) {
      pub.send(zmq::str_buffer("x"), zmq::send_flags::none);
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
  }
  close(fds[1]);
  char buffer[256];
  const ssize_t n = read(fds[0], buffer, sizeof buffer);
  close(fds[0]);
  *endpoint = n > 0 ? std::string(buffer, static_cast<size_t>(n)) : "";
  return pid;
}

// A box that hangs keeps its TCP connection open: the heartbeat finds it out (closing the
// connection, reported like a box that went away), and the box is heard again once it runs.
TEST(Inputs, AHungPublisherIsFoundOutByTheHeartbeatAndHeardAgainWhenItRuns) {
  std::string endpoint;
  const pid_t box = ForkPublisher(&endpoint);
  ASSERT_GT(box, 0);
  ASSERT_FALSE(endpoint.empty());
  {
    zmq::context_t context;
    Session session;
    session.inputs = {endpoint};
    InputSockets inputs(context);
    std::string error;
    ASSERT_TRUE(inputs.Open(session, &error)) << error;
    EXPECT_GE(Listen(inputs, 30, [](int received, size_t) { return received >= 10; }).first, 10);
    kill(box, SIGSTOP);  // hung: its connection stays open, nothing answers
    const auto stopped = std::chrono::steady_clock::now();
    const auto [_, closed] = Listen(inputs, 30, [](int, size_t closed) { return closed > 0; });
    const double found_s =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - stopped).count();
    EXPECT_EQ(closed, std::vector<size_t>{0});
    EXPECT_GE(found_s, 0.5 * InputSockets::kHeartbeatTimeoutMs / 1000.0);  // not by a close
    kill(box, SIGCONT);
    EXPECT_GE(Listen(inputs, 30, [](int received, size_t) { return received >= 10; }).first, 10);
  }
  kill(box, SIGKILL);
  waitpid(box, nullptr, 0);
}

}  // namespace
}  // namespace mocap
