#include "mocap/prior.h"

#include "json_util.h"

namespace mocap {

bool PosePrior::IsValid(std::string* error) const {
  if (dof() == 0 || basis.rows() != dof() || sigma.size() != rank() || rank() == 0) {
    *error = "prior sizes disagree";
    return false;
  }
  if (!mean.allFinite() || !basis.allFinite() || !sigma.allFinite() || (sigma.array() <= 0).any()) {
    *error = "prior has non-finite values or non-positive sigma";
    return false;
  }
  const Eigen::MatrixXd gram = basis.transpose() * basis;
  if ((gram - Eigen::MatrixXd::Identity(rank(), rank())).cwiseAbs().maxCoeff() > 1e-6) {
    *error = "prior basis columns are not orthonormal";
    return false;
  }
  return true;
}

static bool ParsePosePriorJsonUnguarded(const std::string& text, PosePrior* out,
                                        std::string* error) {
  nlohmann::json j;
  if (!internal::ParseJson(text, &j, error)) return false;
  if (!j.is_object() || j.value("format", "") != "mocap.prior/1" || !j.contains("dof") ||
      !j["dof"].is_number_integer() || !j.contains("basis") || !j["basis"].is_array() ||
      !j.contains("mean") || !j.contains("sigma")) {
    *error = "not a mocap.prior/1 file";
    return false;
  }
  // dof is checked against the mean's length before anything is allocated by it.
  const int64_t d = j["dof"].get<int64_t>();
  const int64_t k = static_cast<int64_t>(j["basis"].size());
  if (d <= 0 || k <= 0 || d > kMaxPriorDof || k > d || !j["mean"].is_array() ||
      static_cast<int64_t>(j["mean"].size()) != d) {
    *error = "prior needs 0 < components <= dof <= " + std::to_string(kMaxPriorDof) +
             " and a mean of dof values";
    return false;
  }
  PosePrior prior;
  prior.mean.resize(d);
  prior.sigma.resize(k);
  prior.basis.resize(d, k);
  if (!internal::ReadVector(j["mean"], d, prior.mean.data()) ||
      !internal::ReadVector(j["sigma"], k, prior.sigma.data())) {
    *error = "prior mean or sigma malformed";
    return false;
  }
  for (int c = 0; c < k; ++c) {
    if (!internal::ReadVector(j["basis"][c], d, prior.basis.col(c).data())) {
      *error = "prior basis component " + std::to_string(c) + " malformed";
      return false;
    }
  }
  if (!prior.IsValid(error)) return false;
  *out = std::move(prior);
  return true;
}

bool ParsePosePriorJson(const std::string& text, PosePrior* out, std::string* error) {
  return internal::Guarded(error, [&] { return ParsePosePriorJsonUnguarded(text, out, error); });
}

bool LoadPosePriorJson(const std::string& path, PosePrior* out, std::string* error) {
  return internal::LoadFile(
      path, error, [&](const std::string& text) { return ParsePosePriorJson(text, out, error); });
}

std::string PosePriorToJson(const PosePrior& prior) {
  nlohmann::json j;
  j["format"] = "mocap.prior/1";
  j["dof"] = prior.dof();
  j["mean"] = std::vector<double>(prior.mean.data(), prior.mean.data() + prior.dof());
  j["sigma"] = std::vector<double>(prior.sigma.data(), prior.sigma.data() + prior.rank());
  j["basis"] = nlohmann::json::array();
  for (int c = 0; c < prior.rank(); ++c) {
    j["basis"].push_back(
        std::vector<double>(prior.basis.col(c).data(), prior.basis.col(c).data() + prior.dof()));
  }
  return j.dump();
}

}  // namespace mocap
