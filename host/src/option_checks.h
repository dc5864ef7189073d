// Collects one message per failing condition of an options struct, so that IsValid says
// which fields are wrong and why rather than only that something is.
#ifndef MOCAP_SRC_OPTION_CHECKS_H_
#define MOCAP_SRC_OPTION_CHECKS_H_

#include <string>
#include <vector>

namespace mocap {
namespace internal {

class OptionChecks {
 public:
  // prefix is put before every field name ("position." for a term of SolverOptions).
  explicit OptionChecks(std::string prefix = "") : prefix_(std::move(prefix)) {}

  // Unless ok, notes "<prefix><name> = <value> is out of range (must be <rule>)".
  void Expect(bool ok, const char* name, double value, const char* rule);
  // Unless ok, notes "<prefix><name> is out of range (must be <rule>)": for vectors.
  void Expect(bool ok, const char* name, const char* rule);
  // Notes the messages of a nested struct's IsValid when it failed.
  void Nested(bool valid, const std::string& messages);

  // True when every condition held; else *error (may be null) is the messages joined by "; ".
  bool Done(std::string* error) const;

 private:
  std::string prefix_;
  std::vector<std::string> failures_;
};

}  // namespace internal
}  // namespace mocap

#endif  // MOCAP_SRC_OPTION_CHECKS_H_
