#pragma once
// An elastic network: one trained network whose subnets (subnet.h) all run, so the search and
// the dynamic pruning choose among them by inference instead of training each one (the
// Once-for-All idea on a CG-enhanced network).
//
// Every layer group has an elastic width: a prefix of its channels, which make_elastic() sorts by
// importance once (L1 magnitude of the weights producing them, the order Once-for-All uses), so
// the first channels matter most; widths are multiples of a quantum between a minimum fraction of
// the full width and the full width. Every residual block has an elastic depth: it can be
// skipped (but for the backbone's fixed blocks, BackboneInfo::fixed_blocks). The space knows the choices; train/elastic_training.h trains them (sandwich rule,
// in-place distillation), search/ picks among them.
//
//   ElasticSpace space(net->spec(), options, block_order);
//   SubnetConfig sub = space.sample(rng);                 // every gene drawn from its choices
//   graph::Graph g = subnet_graph(*net, sub);

#include <map>
#include <nlohmann/json.hpp>
#include <random>
#include <string>
#include <vector>

#include "core/config.h"
#include "core/json_fields.h"
#include "models/arch_spec.h"
#include "models/subnet.h"

namespace cgsr {

struct ElasticOptions {
  int quantum = 4;                  // widths are multiples of this (and the full width)
  double min_width_fraction = 0.25; // of each group's full width
  int min_blocks = 4;               // the fewest residual blocks a subnet keeps
  bool elastic_width = true;
  bool elastic_depth = true;
  std::vector<std::string> fixed_groups;  // layer groups that always keep every channel
  // Formats a subnet may run in: a latency table is measured for each, and the search picks one
  // per subnet. Training is always float32.
  std::vector<Precision> precisions = {Precision::Fp32};
};
config::Schema<ElasticOptions> elastic_options_schema();
// Metadata written before a field existed reads it as its default.
CGSR_JSON_FIELDS_WITH_DEFAULT(ElasticOptions, quantum, min_width_fraction, min_blocks, elastic_width, elastic_depth,
                              fixed_groups, precisions)

// How far a sample may shrink: the fraction of the way from the full width (0) to the smallest
// (1), per dimension. Progressive shrinking opens these over the training.
struct ShrinkLimits {
  double width = 1, depth = 1;
};

class ElasticSpace {
 public:
  // `block_order`: the network's blocks, most important first (the smallest subnet keeps the
  // first min_blocks of them); empty: in index order.
  ElasticSpace(const ArchSpec& spec, ElasticOptions options, std::vector<int> block_order = {});

  const ArchSpec& spec() const { return spec_; }
  const ElasticOptions& options() const { return options_; }
  const std::vector<int>& block_order() const { return block_order_; }

  // The elastic groups (full width, allowed widths ascending), in the spec's order.
  struct Gene {
    std::string group;
    int64_t full = 0;
    std::vector<int64_t> choices;
  };
  const std::vector<Gene>& genes() const { return genes_; }
  int total_blocks() const { return spec_.blocks; }
  int min_blocks() const;

  // full() and smallest() run in float32 (the references, and what training runs).
  SubnetConfig full() const;
  // Every gene at its lowest choice within `limits`, the most important blocks kept.
  SubnetConfig smallest(ShrinkLimits limits = {}) const;
  // Widths drawn uniformly among the allowed ones within `limits`, a block count uniformly, and
  // which blocks uniformly among the subsets of that size; float32 (training and the latency
  // table draw the same subnets whatever the precisions).
  SubnetConfig sample(std::mt19937_64& rng, ShrinkLimits limits = {}) const;
  // A search candidate: sample(), then a precision drawn uniformly among the listed ones.
  SubnetConfig sample_candidate(std::mt19937_64& rng) const;
  // Whether the subnet is one of the space's (allowed widths, enough blocks).
  bool contains(const SubnetConfig& sub) const;
  // Every width rounded to the nearest allowed one, the block count raised to the minimum
  // (restoring the most important missing blocks) and a precision the space does not list
  // replaced by its first: the nearest subnet in the space.
  SubnetConfig repair(SubnetConfig sub) const;

 private:
  int lowest_block_count(double depth_limit) const;
  bool is_fixed_block(int block) const;
  ArchSpec spec_;
  ElasticOptions options_;
  std::vector<int> block_order_;
  std::vector<int> fixed_blocks_;  // blocks every subnet keeps (BackboneInfo::fixed_blocks)
  std::vector<Gene> genes_;
};

// An elastic network ready to train: the network with every layer group's channels sorted by
// importance (it computes the same outputs, up to float summation order) and its space, the
// blocks ranked by importance (importance/block_importance.h).
struct ElasticNetwork {
  SRNetwork network{nullptr};
  ElasticSpace space;
};
// Channels sorted by the magnitude criterion (importance/channel_importance.h).
ElasticNetwork make_elastic(const SRNetworkImpl& net, const ElasticOptions& options);
// Channels sorted by `importance`, any criterion's scores: layer group -> [width], higher first
// (ties keep the channel order). Groups it leaves out keep their order.
ElasticNetwork make_elastic(const SRNetworkImpl& net, const ElasticOptions& options,
                            const std::map<std::string, torch::Tensor>& importance);

// What a model file records of an elastic network (provenance.extra["elastic"]): the options
// and the block order, so a later command rebuilds the same space.
nlohmann::ordered_json elastic_metadata(const ElasticSpace& space);
// The space a model file's metadata describes for `spec`; an Error naming `context` when the
// metadata is missing or malformed.
ElasticSpace elastic_space_from(const ArchSpec& spec, const nlohmann::ordered_json& extra, const std::string& context);

}  // namespace cgsr
