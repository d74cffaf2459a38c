// accelbench: the command-line entry point. Subcommands live in harness/cmd_*.cpp.
#include "harness/cli.h"

int main(int argc, char** argv) {
  return ab::run_cli(argc, argv);
}
