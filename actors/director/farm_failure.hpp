#pragma once
// How the director's parts end a farm: a message and the process's exit status (1: the farm failed; 2: a bad script
// or command line, found before anything started; 128+N: signal N). Thrown, and caught once, in Director::run.
#include <string>

#include "core/result.hpp"

namespace lf {

struct FarmFailure {
  std::string message;
  int status = 1;
};

inline void check(const Status& st) {
  if (!st) throw FarmFailure{st.error().message};
}

}  // namespace lf
