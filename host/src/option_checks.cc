#include "option_checks.h"

#include <sstream>

namespace mocap {
namespace internal {

void OptionChecks::Expect(bool ok, const char* name, double value, const char* rule) {
  if (ok) return;
  std::ostringstream m;
  m << prefix_ << name << " = " << value << " is out of range (must be " << rule << ")";
  failures_.push_back(m.str());
}

void OptionChecks::Expect(bool ok, const char* name, const char* rule) {
  if (!ok) failures_.push_back(prefix_ + name + " is out of range (must be " + rule + ")");
}

void OptionChecks::Nested(bool valid, const std::string& messages) {
  if (!valid) failures_.push_back(messages);
}

bool OptionChecks::Done(std::string* error) const {
  if (failures_.empty()) return true;
  if (error != nullptr) {
    error->clear();
    for (const std::string& f : failures_) *error += (error->empty() ? "" : "; ") + f;
  }
  return false;
}

}  // namespace internal
}  // namespace mocap
