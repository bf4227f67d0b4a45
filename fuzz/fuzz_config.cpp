// Fuzz target for the YAML config parser: the document (core/config), every subcommand's schema,
// and the stage sections of a `cgsr run` config parsed with the schemas of their subcommands,
// as cgsr run parses them. Every input must parse or be rejected with cgsr::Error; any other
// exception, crash or sanitizer report is a bug. Seeds: configs/.

#include <cstddef>
#include <cstdint>
#include <string>

#include "cli/commands/data_check.h"
#include "cli/commands/report.h"
#include "core/config.h"
#include "core/error.h"
#include "core/yaml_json.h"
#include "eval/evaluation.h"
#include "pipeline/bench.h"
#include "pipeline/eval_stage.h"
#include "pipeline/export_stage.h"
#include "pipeline/pipeline.h"
#include "pipeline/prune_stage.h"
#include "pipeline/render_stage.h"
#include "pipeline/search_stage.h"
#include "pipeline/train_stage.h"

namespace {
using namespace cgsr;

template <class T>
void parse_with(const config::Document& doc, const config::Schema<T>& schema) {
  try {
    const T options = config::parse_document(doc, schema);
    const YAML::Node resolved = schema.emit(options);
    (void)config::to_yaml(resolved);  // what config.yaml would hold
    (void)yaml_to_json(resolved);     // what results.json and model files record
  } catch (const Error&) {
  }
}

template <class T>
void parse_block_with(const config::Block& block, const config::Schema<T>& schema) {
  if (!block.node) return;
  try {
    T out{};
    schema.parse(block.node, out, block.cursor());
  } catch (const Error&) {
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace cgsr::cli;
  config::Document doc;
  try {
    doc = config::Document::parse(std::string(reinterpret_cast<const char*>(data), size), "fuzz.yaml");
  } catch (const Error&) {
    return 0;
  }
  parse_with(doc, render_schema());
  parse_with(doc, train_schema());
  parse_with(doc, search_command_schema());
  parse_with(doc, prune_command_schema());
  parse_with(doc, eval_schema());
  parse_with(doc, export_schema());
  parse_with(doc, bench_schema());
  parse_with(doc, report_schema());
  parse_with(doc, data_check_schema());
  try {
    const PipelineOptions pipeline = config::parse_document(doc, pipeline_schema());
    parse_block_with(pipeline.train, train_schema());
    parse_block_with(pipeline.enhance, enhance_stage_schema());
    parse_block_with(pipeline.elastic, elastic_stage_schema());
    parse_block_with(pipeline.search, search_command_schema());
    parse_block_with(pipeline.prune, prune_command_schema());
    parse_block_with(pipeline.eval, eval_schema_fields());
  } catch (const Error&) {
  }
  return 0;
}
