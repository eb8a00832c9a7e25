// flexfarm: simulate flexible robot arms, one at a time or by the thousand.
#include <CLI/CLI.hpp>

#include <algorithm>
#include <cstdio>
#include <exception>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include "apps/verbs.hpp"
#include "jobs/mpi.hpp"
#include "common/closest.hpp"
#include "common/errors.hpp"
#include "common/text.hpp"
#include "common/isa.hpp"
#include "common/version.hpp"

int main(int argc, char** argv) {
  ff::MpiSession session(&argc, &argv);  // one rank of one unless started by mpirun
  ff::set_mpi(&session);
  CLI::App app{"flexfarm: simulation farm for flexible robot manipulators (PNL Flexible Beam Testbed and kin)"};
  app.require_subcommand(1);
  // The version and the vector width the kernels run at (common/isa.hpp; FLEXFARM_ISA narrows it).
  app.set_version_flag("--version", [] { return "flexfarm " + ff::describe_version() + ", kernels " + ff::describe_isa(); });
  ff::add_modes_verb(app);
  ff::add_simulate_verb(app);
  ff::add_run_verb(app);
  ff::add_merge_verb(app);
  ff::add_table_verb(app);
  ff::add_history_verb(app);
  ff::add_diff_verb(app);
  ff::add_plot_verb(app);
  ff::add_animate_verb(app);
  ff::add_view_verb(app);
  ff::add_record_verb(app);
  ff::add_diagnose_verb(app);
  ff::add_calibrate_verb(app);
  ff::add_compare_verb(app);
  try {
    ff::active_isa();  // a bad FLEXFARM_ISA stops here, before any kernel runs
    // A first word that is neither a verb nor an option: the closest verb (CLI11 says "A subcommand is required").
    if (argc > 1 && argv[1][0] != '-') {
      std::vector<std::string> verbs;
      for (const CLI::App* v : app.get_subcommands([](CLI::App*) { return true; })) verbs.push_back(v->get_name());
      if (std::find(verbs.begin(), verbs.end(), argv[1]) == verbs.end())
        throw ff::ExitError(std::string("unknown verb '") + argv[1] + "'" + ff::format_did_you_mean(argv[1], verbs) +
                                " (flexfarm --help lists the verbs)",
                            2);
    }
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    std::ostringstream err;  // a bad option's value is shown as text, escape sequences and all
    const int code = app.exit(e, std::cout, err);  // --help (0), bad options
    ff::print_safe(stderr, "%s", err.str().c_str());
    return code == 0 ? 0 : 2;  // bad input is exit 2, as for a bad file (flexfarm diff: 1 is a regression)
  } catch (const ff::ExitError& e) {
    if (*e.what()) ff::print_safe(stderr, "flexfarm: error: %s\n", e.what());
    return e.code;
  } catch (const ff::ConfigError& e) {
    ff::print_safe(stderr, "flexfarm: error: %s\n", e.what());  // a name's escape sequence shown as text
    return 2;
  } catch (const std::exception& e) {
    ff::print_safe(stderr, "flexfarm: error: %s\n", e.what());  // a name's escape sequence shown as text
    return 1;
  }
  return 0;
}
