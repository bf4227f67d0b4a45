// cgsr: lightweight super-resolution for real-time graphics. main() only wires subcommands
// and turns errors into messages and exit codes (2 for user errors and the machine's limits, 1
// for internal ones: cli/failure.h).

#include <CLI/CLI.hpp>

#include "cli/command.h"
#include "cli/failure.h"
#include "cli/commands/ablate.h"
#include "cli/commands/bench.h"
#include "cli/commands/data_check.h"
#include "cli/commands/eval.h"
#include "cli/commands/export.h"
#include "cli/commands/info.h"
#include "cli/commands/prune.h"
#include "cli/commands/render.h"
#include "cli/commands/report.h"
#include "cli/commands/run.h"
#include "cli/commands/search.h"
#include "cli/commands/train.h"
#include "core/logging.h"

int main(int argc, char** argv) {
  using namespace cgsr::cli;
  CLI::App app{"cgsr: rendering-information guided super-resolution for real-time graphics"};
  app.set_version_flag("--version", std::string("cgsr ") + CGSR_VERSION);
  app.require_subcommand(1);
  app.fallthrough();  // global options may also follow the subcommand
  add_global_options(app);

  setup_info(app);
  setup_render(app);
  setup_data(app);
  setup_bench(app);
  setup_train(app);
  setup_eval(app);
  setup_search(app);
  setup_prune(app);
  setup_report(app);
  setup_export(app);
  setup_ablate(app);
  setup_run(app);

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);
    return code == 0 ? 0 : 2;
  } catch (...) {
    const int code = report_failure(std::current_exception(), globals().verbose);
    cgsr::finish_log_file();
    return code;
  }
  cgsr::finish_log_file();
  return 0;
}
