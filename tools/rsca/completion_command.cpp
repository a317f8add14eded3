// rsca completion bash: a bash completion script made from the CLI's own commands and options,
// so that it can never disagree with them. Load it with `source <(rsca completion bash)`, or
// install it as /usr/share/bash-completion/completions/rsca.
#include <string>
#include <vector>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "commands.hpp"
#include "exit_codes.hpp"

namespace rsca::cli {
namespace {

// One command: its path ("rsca:ls"), the subcommands and options that may follow it.
struct CompletionEntry {
  std::string path;
  std::vector<std::string> commands;
  std::vector<std::string> options;
};

std::vector<std::string> options_of(const CLI::App &app) {
  std::vector<std::string> out;
  for (const CLI::Option *option : app.get_options()) {
    if (!option->nonpositional())
      continue;
    for (const auto &name : option->get_lnames())
      out.push_back("--" + name);
    for (const auto &name : option->get_snames())
      out.push_back("-" + name);
  }
  return out;
}

void collect(const CLI::App &app, const std::string &path,
             const std::vector<std::string> &inherited, std::vector<CompletionEntry> &out) {
  CompletionEntry entry{path, {}, inherited};
  const auto own = options_of(app);
  entry.options.insert(entry.options.end(), own.begin(), own.end());
  for (const CLI::App *sub : app.get_subcommands({}))
    entry.commands.push_back(sub->get_name());
  out.push_back(entry);
  // Global options may follow any subcommand (the root falls through).
  const auto &passed_on = path == "rsca" ? entry.options : inherited;
  for (const CLI::App *sub : app.get_subcommands({}))
    collect(*sub, path + ":" + sub->get_name(), passed_on, out);
}

std::string bash_script(const CLI::App &root) {
  std::vector<CompletionEntry> entries;
  collect(root, "rsca", {}, entries);
  std::string steps;
  std::string choices;
  for (const auto &e : entries) {
    for (const auto &c : e.commands)
      steps += fmt::format("      {}:{}) path=\"$path:$w\" ;;\n", e.path, c);
    choices += fmt::format("    {}) commands=\"{}\"; options=\"{}\" ;;\n", e.path,
                           fmt::join(e.commands, " "), fmt::join(e.options, " "));
  }
  return fmt::format(
      "# bash completion for rsca (made by `rsca completion bash`)\n"
      "_rsca() {{\n"
      "  local cur=\"${{COMP_WORDS[COMP_CWORD]}}\" path=rsca i w commands=\"\" options=\"\"\n"
      "  for ((i = 1; i < COMP_CWORD; i++)); do\n"
      "    w=\"${{COMP_WORDS[i]}}\"\n"
      "    case \"$path:$w\" in\n"
      "{}"
      "    esac\n"
      "  done\n"
      "  case \"$path\" in\n"
      "{}"
      "  esac\n"
      "  if [[ \"$cur\" == -* ]]; then\n"
      "    COMPREPLY=($(compgen -W \"$options\" -- \"$cur\"))\n"
      "  elif [[ -n \"$commands\" ]]; then\n"
      "    COMPREPLY=($(compgen -W \"$commands\" -- \"$cur\"))\n"
      "  else\n"
      "    COMPREPLY=($(compgen -f -- \"$cur\"))\n"
      "  fi\n"
      "}}\n"
      "complete -o filenames -F _rsca rsca\n",
      steps, choices);
}

} // namespace

void add_completion_command(CLI::App &app, int &exit_code) {
  auto *cmd = app.add_subcommand("completion", "Print a shell completion script (bash): "
                                               "source <(rsca completion bash)");
  auto shell = std::make_shared<std::string>();
  cmd->add_option("shell", *shell, "The shell")->required()->check(CLI::IsMember({"bash"}));
  // The callback holds `shell`: the option writes into it when the command line is parsed.
  cmd->callback([&app, &exit_code, shell] {
    fmt::print("{}", bash_script(app));
    exit_code = kOk;
  });
}

} // namespace rsca::cli
