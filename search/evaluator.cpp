#include "search/evaluator.h"

namespace cgsr {

nlohmann::ordered_json to_json(const CandidateScore& s) {
  nlohmann::ordered_json j;
  j["val_psnr"] = s.val_psnr;
  j["val_ssim"] = s.val_ssim;
  j["image_loss"] = s.image_loss;
  j["geometry_loss"] = s.geometry_loss;
  j["params"] = s.params;
  j["macs"] = s.macs;
  j["latency_ms"] = s.latency_ms ? nlohmann::ordered_json(*s.latency_ms) : nullptr;
  j["train_seconds"] = s.train_seconds;
  return j;
}

void Evaluator::evaluate_batch(const std::vector<ArchSpec>& specs,
                               const std::function<void(size_t, const CandidateScore&)>& done) {
  for (size_t i = 0; i < specs.size(); ++i) done(i, evaluate(specs[i]));
}

CandidateScore candidate_score_from_json(const nlohmann::json& j) {
  CandidateScore s;
  s.val_psnr = j.at("val_psnr");
  s.val_ssim = j.at("val_ssim");
  s.image_loss = j.at("image_loss");
  s.geometry_loss = j.at("geometry_loss");
  s.params = j.at("params");
  s.macs = j.at("macs");
  if (!j.at("latency_ms").is_null()) s.latency_ms = j.at("latency_ms").get<double>();
  s.train_seconds = j.at("train_seconds");
  return s;
}

}  // namespace cgsr
