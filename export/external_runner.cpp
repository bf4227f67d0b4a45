#include "export/external_runner.h"

#include <torch/torch.h>

#include "core/atomic_file.h"
#include "core/error.h"
#include "export/raw_tensor.h"

namespace cgsr {
namespace fs = std::filesystem;

ExternalJob::ExternalJob(std::string runtime, const std::string& prefix)
    : runtime_(std::move(runtime)), dir_(prefix) {}

nlohmann::ordered_json ExternalJob::write_inputs(const NamedTensors& inputs, const std::string& stem) const {
  auto entries = nlohmann::ordered_json::array();
  for (const auto& [name, t] : inputs) {
    const fs::path path = file(stem + "." + name + ".in.f32");
    write_raw_float32(path, t);
    entries.push_back({{"name", name}, {"shape", t.sizes().vec()}, {"file", path.string()}});
  }
  return entries;
}

nlohmann::json ExternalJob::run(const nlohmann::ordered_json& job, std::vector<std::string> program) const {
  const fs::path job_file = file("job.json"), result_file = file("result.json");
  write_file_atomic(job_file, job.dump());
  program.push_back(job_file.string());
  program.push_back(result_file.string());
  const ProcessResult p = run_process(program);
  if (p.exit_code != 0 || !fs::exists(result_file))
    throw Error(runtime_, "the runner failed (exit " + std::to_string(p.exit_code) + "): " +
                              (p.err.empty() ? p.out : p.err));
  try {
    return nlohmann::json::parse(read_file(result_file));
  } catch (const nlohmann::json::exception& e) {
    throw Error(runtime_, std::string("unreadable runner result: ") + e.what(), ErrorKind::Internal);
  }
}

}  // namespace cgsr
