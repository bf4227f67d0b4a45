#pragma once
// What the options of every job carry (each stage of `cgsr run`, each subcommand), so that the
// config.yaml of a run directory alone reproduces the run: the seed and the thread count.

#include <cstdint>

#include "core/config.h"

namespace cgsr {

struct RunSettings {
  int64_t seed = 0;
  int threads = 0;
};

template <class T>
void add_run_settings(config::Schema<T>& schema) {
  schema.field("seed", static_cast<int64_t T::*>(&RunSettings::seed), "seed for every random number generator")
      .at_least(0);
  schema.field("threads", static_cast<int T::*>(&RunSettings::threads), "LibTorch and TBB threads (0 = all)")
      .range(0, 1024);
}

}  // namespace cgsr
