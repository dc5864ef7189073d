// A fresh CURVE key pair (Z85) for the daemon's tests.
#ifndef MOCAP_DAEMON_CURVE_TEST_KEYS_H_
#define MOCAP_DAEMON_CURVE_TEST_KEYS_H_

#include <zmq.h>

#include <string>

namespace mocap::testing {

struct KeyPair {
  std::string pub, secret;
  KeyPair() {
    char p[41], s[41];
    zmq_curve_keypair(p, s);
    pub = p;
    secret = s;
  }
};

}  // namespace mocap::testing

#endif  // MOCAP_DAEMON_CURVE_TEST_KEYS_H_
