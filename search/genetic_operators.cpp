#include "search/genetic_operators.h"

#include <algorithm>

namespace cgsr {

namespace {
bool keeps(const SubnetConfig& sub, int block) { return std::binary_search(sub.blocks.begin(), sub.blocks.end(), block); }
}  // namespace

SubnetConfig mutate(const ElasticSpace& space, const SubnetConfig& sub, double rate, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(0, 1);
  SubnetConfig out = space.repair(sub);
  for (const auto& gene : space.genes()) {
    if (gene.choices.size() < 2 || u(rng) >= rate) continue;
    const auto at = std::find(gene.choices.begin(), gene.choices.end(), out.widths.at(gene.group));
    size_t i = static_cast<size_t>(at - gene.choices.begin());
    if (i == 0) ++i;
    else if (i + 1 == gene.choices.size()) --i;
    else i = u(rng) < 0.5 ? i - 1 : i + 1;
    out.widths[gene.group] = gene.choices[i];
  }
  if (space.min_blocks() < space.total_blocks()) {
    std::vector<int> blocks;
    for (int b = 0; b < space.total_blocks(); ++b) {
      const bool kept = keeps(out, b);
      if (kept != (u(rng) < rate)) blocks.push_back(b);
    }
    out.blocks = blocks;
  }
  const auto& precisions = space.options().precisions;
  if (precisions.size() > 1 && u(rng) < rate) {  // another of the listed formats
    std::vector<Precision> others;
    for (Precision p : precisions)
      if (p != out.precision) others.push_back(p);
    out.precision = others[std::uniform_int_distribution<size_t>(0, others.size() - 1)(rng)];
  }
  return space.repair(out);
}

SubnetConfig crossover(const ElasticSpace& space, const SubnetConfig& a, const SubnetConfig& b, std::mt19937_64& rng) {
  std::bernoulli_distribution coin(0.5);
  const SubnetConfig ra = space.repair(a), rb = space.repair(b);
  SubnetConfig out;
  for (const auto& gene : space.genes()) out.widths[gene.group] = (coin(rng) ? ra : rb).widths.at(gene.group);
  for (int block = 0; block < space.total_blocks(); ++block)
    if (keeps(coin(rng) ? ra : rb, block)) out.blocks.push_back(block);
  if (space.options().precisions.size() > 1) out.precision = (coin(rng) ? ra : rb).precision;
  return space.repair(out);
}

}  // namespace cgsr
