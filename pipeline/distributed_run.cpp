#include "pipeline/distributed_run.h"

#include <spdlog/spdlog.h>

#include "core/error.h"
#include "core/hash.h"
#include "core/runtime.h"

namespace cgsr {

std::filesystem::path rank_run_dir(const distributed::DistributedOptions& options, const std::filesystem::path& out) {
  if (!options.enabled() || options.rank == 0) return out;
  return out / ("rank" + std::to_string(options.rank));
}

std::unique_ptr<distributed::World> join_run(const distributed::DistributedOptions& options,
                                              const std::string& job) {
  auto world = distributed::World::join(options);
  const std::string mine = std::to_string(fnv1a64(job)) + " " + std::to_string(thread_count());
  const auto split = [](const std::string& s) { return std::make_pair(s.substr(0, s.find(' ')), s.substr(s.find(' ') + 1)); };
  // Every rank posts before anyone judges, so a mismatch fails every rank at once.
  const auto all = world->gather("job", mine);
  const std::string reference = world->broadcast("job-reference", mine);
  for (size_t r = 1; r < all.size(); ++r)
    if (split(all[r]).first != split(mine).first)
      throw Error(world->describe(), "rank " + std::to_string(r) + " was started on a different job (parent model, "
                                     "data, seed or training settings differ); start every rank with the same config");
  if (split(mine).first != split(reference).first)
    throw Error(world->describe(), "this rank was started on a different job than rank 0 (parent model, data, "
                                   "seed or training settings differ); start every rank with the same config");
  for (size_t r = 1; r < all.size(); ++r)
    if (split(all[r]).second != split(mine).second)
      spdlog::warn("distributed: rank {} runs {} threads, rank 0 runs {}: results match a 1-process run only within "
                   "float tolerance (pass the same --threads to every rank for identical ones)",
                   r, split(all[r]).second, split(mine).second);
  return world;
}

YAML::Node without_distribution(const YAML::Node& resolved) {
  if (!resolved.IsMap() || !resolved["distributed"]) return resolved;
  YAML::Node copy = YAML::Clone(resolved);
  copy.remove("distributed");
  return copy;
}

}  // namespace cgsr
