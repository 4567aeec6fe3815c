// quijibo: from a mesh to a quaternion Julia set of its shape.
#include <csignal>
#include <cstdio>
#include <exception>

#include "experiments/cli/cli.h"
#include "util/error.h"
#include "util/progress.h"

namespace {

// `-q` is accepted after any subcommand too (`quijibo optimize ... -q`), bound to the same flag as
// before it; a subcommand with its own --quiet (run) keeps it.
void AddQuietEverywhere(CLI::App& app, bool& quiet) {
  for (CLI::App* sub : app.get_subcommands([](CLI::App* s) { return !s->get_name().empty(); })) {
    if (sub->get_option_no_throw("--quiet") == nullptr) sub->add_flag("-q,--quiet", quiet, "No progress on stderr");
    AddQuietEverywhere(*sub, quiet);
  }
}

}  // namespace

int main(int argc, char** argv) {
  // Under a file-size limit (ulimit -f) an over-long write then fails with EFBIG and is reported
  // like a full disk (file and reason, no partial file), instead of SIGXFSZ killing us mid-file.
  std::signal(SIGXFSZ, SIG_IGN);
  CLI::App app{
      "quijibo: quaternion Julia sets shaped like a mesh (QUIJIBO, Kim 2015), with the shape\n"
      "modulus (2023) and portals (2024) for comparison. See README.md and docs/."};
  bool quiet = false;
  quijibo::cli::SetUpApp(app, "quijibo", quiet);
  quijibo::cli::AddCommands(app);
  AddQuietEverywhere(app, quiet);
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    std::fprintf(stderr, "quijibo: error: %s (see --help)\n", e.what());
    return 2;
  } catch (const quijibo::Interrupted& e) {
    std::fprintf(stderr, "quijibo: %s\n", e.what());
    return 128 + e.signal;
  } catch (const quijibo::Error& e) {
    std::fprintf(stderr, "quijibo: error: %s\n", e.what());
    return 1;
  } catch (const std::bad_alloc&) {
    std::fprintf(stderr, "quijibo: error: out of memory\n");
    return 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "quijibo: error: %s\n", e.what());
    return 1;
  }
  return 0;
}
