// SolverOptions and SyncOptions as the session file's "solver" and "sync" objects.
//
// Both are derived from the fields each struct names (VisitFields). Keys left out keep their
// defaults. An unknown key or a value of the wrong type is an error naming the key, never
// ignored: an option misspelt in a session file must not silently fall back to its default.
//
// "solver": every field is a key of the same name; a term (TermOptions) is an object of its
// own fields, e.g. {"position": {"weight": 0.04}}; "loss" is "trivial", "cauchy" or "huber";
// "accel_at_rest" is [x, y, z]; a number may be null, read as NaN (unknown): "floor_height"
// (no floor estimate) takes it, every other field's range check refuses it.
#ifndef MOCAP_DAEMON_OPTIONS_JSON_H_
#define MOCAP_DAEMON_OPTIONS_JSON_H_

#include <nlohmann/json_fwd.hpp>
#include <string>
#include <vector>

#include "mocap/solver_options.h"
#include "mocap/stream_sync.h"

namespace mocap {

// Reads the keys of j into *options (the others keep their values), then checks the result
// (SolverOptions::IsValid). False with *error naming the key or the condition.
bool ReadSolverOptions(const nlohmann::json& j, SolverOptions* options, std::string* error);
// The same from JSON text.
bool ParseSolverOptionsJson(const std::string& text, SolverOptions* options, std::string* error);

// Every field of options, as ReadSolverOptions reads them back.
std::string SolverOptionsToJson(const SolverOptions& options);

// Every key ReadSolverOptions accepts, a term's fields as "term.field".
std::vector<std::string> SolverOptionKeys();

// "sync": a time field is a key in milliseconds ("max_wait_ns" is "max_wait_ms"), the rate
// keeps its name, every value is a number; max_pending_frames, a bound on the host's memory
// rather than a setting of the studio, is not a key. Reads the keys of j into *sync, then
// checks the result (SyncOptions::IsValid).
bool ReadSyncOptions(const nlohmann::json& j, SyncOptions* sync, std::string* error);
// The same from JSON text.
bool ParseSyncOptionsJson(const std::string& text, SyncOptions* sync, std::string* error);
// Every key ReadSyncOptions accepts, in the fields' order.
std::vector<std::string> SyncOptionKeys();

}  // namespace mocap

#endif  // MOCAP_DAEMON_OPTIONS_JSON_H_
