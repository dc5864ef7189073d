#include "zap_handler.h"

#include <zmq.h>

#include <iterator>
#include <zmq_addon.hpp>

namespace mocap {
namespace {

// Request frames: version, request id, domain, address, routing id, mechanism, credentials.
constexpr size_t kRequestFrames = 7;

}  // namespace

ZapHandler::ZapHandler(zmq::context_t& context, const std::vector<std::string>& allowed)
    : socket_(context, zmq::socket_type::rep), allowed_(allowed.begin(), allowed.end()) {
  socket_.set(zmq::sockopt::linger, 0);
  socket_.bind("inproc://zeromq.zap.01");
}

void ZapHandler::Handle() {
  std::vector<zmq::message_t> request;
  for (;;) {
    request.clear();
    if (!zmq::recv_multipart(socket_, std::back_inserter(request), zmq::recv_flags::dontwait))
      return;
    bool ok = false;
    if (request.size() >= kRequestFrames && request[5].to_string_view() == "CURVE" &&
        request[6].size() == 32) {
      char z85[41];
      zmq_z85_encode(z85, static_cast<const uint8_t*>(request[6].data()), 32);
      ok = allowed_.count(z85) > 0;
    }
    (ok ? accepted_ : refused_)++;
    const std::string id = request.size() > 1 ? request[1].to_string() : "";
    std::vector<zmq::const_buffer> reply = {zmq::str_buffer("1.0"),
                                            zmq::buffer(id),
                                            zmq::buffer(ok ? "200" : "400", 3),
                                            zmq::buffer(ok ? "OK" : "key not allowed", ok ? 2 : 15),
                                            zmq::str_buffer(""),
                                            zmq::str_buffer("")};
    zmq::send_multipart(socket_, reply);
  }
}

}  // namespace mocap
