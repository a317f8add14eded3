// rsca completion bash|zsh: a completion script made from the CLI's own commands and options,
// so that it can never disagree with them. Load it with `source <(rsca completion bash)` (zsh:
// `source <(rsca completion zsh)`), or install it as /usr/share/bash-completion/completions/rsca.
// A command's arguments complete by their kind (positional_kinds below): live names of the
// running domain (`rsca completion words KIND` asks it, briefly), fixed words, or files.
#include <algorithm>
#include <set>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "commands.hpp"
#include "completion_words.hpp"
#include "exit_codes.hpp"

namespace rsca::cli {
namespace {

// What each command's positional arguments complete with, by "path:argument" (the path as
// `collect` makes it). A kind is a list of sources: `apps`, `installed`, `nodes`, `devices`,
// `channels` (live names), `files`, or fixed words after `=` ("=apps nodes"). A positional
// missing here completes with files, and the script says so in a comment that a test looks for:
// a new command's arguments are given a kind when it is added.
const std::map<std::string, std::string> &positional_kinds() {
  static const std::map<std::string, std::string> kinds{
      {"rsca:validate:paths", "files"},
      {"rsca:show:what", "apps files"},
      {"rsca:install:sad", "files"},
      {"rsca:uninstall:name", "installed"},
      {"rsca:launch:application", "installed files"},
      {"rsca:connect:uses", "apps"},
      {"rsca:connect:provides", "apps"},
      {"rsca:disconnect:id", ""},
      {"rsca:channel:create:name", ""},
      {"rsca:channel:destroy:name", "channels"},
      {"rsca:start:app", "apps"},
      {"rsca:stop:app", "apps"},
      {"rsca:release:app", "apps"},
      {"rsca:configure:target", "apps devices"},
      {"rsca:configure:values", ""},
      {"rsca:query:target", "apps devices"},
      {"rsca:query:properties", ""},
      {"rsca:plan:application", "installed files"},
      {"rsca:ls:what", "=apps nodes devices installed channels connections"},
      {"rsca:ls:app", "apps"},
      {"rsca:top:app", "apps"},
      {"rsca:logs:target", "apps nodes"},
      {"rsca:echo:port", "apps"},
      {"rsca:hz:port", "apps"},
      {"rsca:new:component:name", ""},
      {"rsca:new:device:name", ""},
      {"rsca:completion:shell", "=bash zsh"},
      {"rsca:completion:words:kind", "=apps installed nodes devices channels"},
  };
  return kinds;
}

// One command: its path ("rsca:ls"), the subcommands and options that may follow it, and the
// kinds of its positional arguments in order.
struct CompletionEntry {
  std::string path;
  std::vector<std::string> commands;
  std::vector<std::string> options;
  std::vector<std::string> positionals;
  std::vector<std::string> unmapped; // positionals without a kind
};

// Its options, and into `valued` those that take a value (the word after one is not an argument).
std::vector<std::string> options_of(const CLI::App &app, std::set<std::string> &valued) {
  std::vector<std::string> out;
  for (const CLI::Option *option : app.get_options()) {
    if (!option->nonpositional())
      continue;
    std::vector<std::string> names;
    for (const auto &name : option->get_lnames())
      names.push_back("--" + name);
    for (const auto &name : option->get_snames())
      names.push_back("-" + name);
    if (option->get_expected_min() > 0 && option->get_type_size() > 0)
      valued.insert(names.begin(), names.end());
    out.insert(out.end(), names.begin(), names.end());
  }
  return out;
}

void collect(const CLI::App &app, const std::string &path,
             const std::vector<std::string> &inherited, std::vector<CompletionEntry> &out,
             std::set<std::string> &valued) {
  CompletionEntry entry{path, {}, inherited, {}, {}};
  for (const auto &option : options_of(app, valued)) // --help is everyone's own
    if (std::find(inherited.begin(), inherited.end(), option) == inherited.end())
      entry.options.push_back(option);
  for (const CLI::Option *option : app.get_options()) {
    if (!option->get_positional())
      continue;
    const std::string key = path + ":" + option->get_name(true);
    const auto kind = positional_kinds().find(key);
    if (kind == positional_kinds().end())
      entry.unmapped.push_back(key);
    entry.positionals.push_back(kind == positional_kinds().end() ? "files" : kind->second);
  }
  for (const CLI::App *sub : app.get_subcommands({}))
    entry.commands.push_back(sub->get_name());
  out.push_back(entry);
  // Global options may follow any subcommand (the root falls through).
  const auto &passed_on = path == "rsca" ? entry.options : inherited;
  for (const CLI::App *sub : app.get_subcommands({}))
    collect(*sub, path + ":" + sub->get_name(), passed_on, out, valued);
}

// The bash array of an entry's positional kinds: ("apps files" "=bash zsh").
std::string kinds_array(const CompletionEntry &e) {
  std::vector<std::string> quoted;
  for (const auto &k : e.positionals)
    quoted.push_back(fmt::format("\"{}\"", k));
  return fmt::format("({})", fmt::join(quoted, " "));
}

std::string bash_script(const CLI::App &root) {
  std::vector<CompletionEntry> entries;
  std::set<std::string> valued;
  collect(root, "rsca", {}, entries, valued);
  std::string steps;
  std::string choices;
  std::string unmapped;
  for (const auto &e : entries) {
    for (const auto &c : e.commands)
      steps += fmt::format("      {}:{}) path=\"$path:$w\"; n=0; continue ;;\n", e.path, c);
    choices += fmt::format("    {}) commands=\"{}\"; options=\"{}\"; kinds={} ;;\n", e.path,
                           fmt::join(e.commands, " "), fmt::join(e.options, " "), kinds_array(e));
    for (const auto &u : e.unmapped)
      unmapped += fmt::format("# no completion kind for {}: files\n", u);
  }
  return fmt::format(
      "# bash completion for rsca (made by `rsca completion bash`)\n"
      "{}"
      "_rsca_words() {{ # the live names of a kind, from the domain; none when it is not there\n"
      "  \"$_rsca_program\" completion words \"$@\" 2>/dev/null\n"
      "}}\n"
      "_rsca() {{\n"
      "  # The words as typed, split at blanks only: bash also splits at ':' (COMP_WORDBREAKS),\n"
      "  # which would cut NODE:DEVICE in two.\n"
      "  local typed=() line cword cur path=rsca i w n=0 skip=0\n"
      "  if [[ -n \"${{COMP_LINE-}}\" ]]; then\n"
      "    line=\"${{COMP_LINE:0:COMP_POINT}}\"\n"
      "    read -ra typed <<<\"$line\"\n"
      "    [[ \"$line\" == *[[:blank:]] || ${{#typed[@]}} -eq 0 ]] && typed+=(\"\")\n"
      "  else\n"
      "    typed=(\"${{COMP_WORDS[@]}}\")\n"
      "  fi\n"
      "  cword=$((${{#typed[@]}} - 1))\n"
      "  cur=\"${{typed[cword]}}\"\n"
      "  _rsca_program=\"${{typed[0]}}\"\n"
      "  local commands=\"\" options=\"\" kinds=() kind source words=\"\" live=\"\" files=0\n"
      "  local valued=\" {} \"\n"
      "  for ((i = 1; i < cword; i++)); do\n"
      "    w=\"${{typed[i]}}\"\n"
      "    if ((skip)); then skip=0; continue; fi\n"
      "    case \"$path:$w\" in\n"
      "{}"
      "    esac\n"
      "    if [[ \"$w\" == -* ]]; then\n"
      "      [[ \"$w\" != *=* && \"$valued\" == *\" $w \"* ]] && skip=1\n"
      "      continue\n"
      "    fi\n"
      "    n=$((n + 1))\n"
      "  done\n"
      "  case \"$path\" in\n"
      "{}"
      "  esac\n"
      "  if [[ \"$cur\" == -* ]]; then\n"
      "    COMPREPLY=($(compgen -W \"$options\" -- \"$cur\"))\n"
      "    return\n"
      "  fi\n"
      "  ((n == 0)) && words=\"$commands\"\n"
      "  if ((${{#kinds[@]}} > 0)); then\n"
      "    if ((n < ${{#kinds[@]}})); then kind=\"${{kinds[n]}}\"; else kind=\"${{kinds[-1]}}\"; "
      "fi\n"
      "    if [[ \"$kind\" == =* ]]; then\n"
      "      words+=\" ${{kind#=}}\"\n"
      "    else\n"
      "      for source in $kind; do\n"
      "        if [[ \"$source\" == files ]]; then files=1; else live+=\" $source\"; fi\n"
      "      done\n"
      "      [[ -z \"$live\" ]] || words+=\" $(_rsca_words $live)\"\n"
      "    fi\n"
      "  fi\n"
      "  COMPREPLY=($(compgen -W \"$words\" -- \"$cur\"))\n"
      "  if ((files)); then COMPREPLY+=($(compgen -f -- \"$cur\")); fi\n"
      "  # bash replaces only what follows the last ':' of the word.\n"
      "  if [[ \"$cur\" == *:* && \"${{COMP_WORDBREAKS-}}\" == *:* ]]; then\n"
      "    COMPREPLY=(\"${{COMPREPLY[@]#\"${{cur%:*}}:\"}}\")\n"
      "  fi\n"
      "}}\n"
      "complete -o filenames -F _rsca rsca\n",
      unmapped, fmt::join(valued, " "), steps, choices);
}

// zsh runs the bash script through its bash completion layer (bashcompinit).
std::string zsh_script(const CLI::App &root) {
  return "#compdef rsca\n# zsh completion for rsca (made by `rsca completion zsh`)\n"
         "autoload -U +X compinit && compinit\n"
         "autoload -U +X bashcompinit && bashcompinit\n" +
         bash_script(root);
}

} // namespace

void add_completion_command(CLI::App &app, const GlobalOptions &global, int &exit_code) {
  auto *cmd = app.add_subcommand("completion", "Print a shell completion script (bash or zsh): "
                                               "source <(rsca completion bash)");
  auto shell = std::make_shared<std::string>();
  cmd->add_option("shell", *shell, "The shell")->check(CLI::IsMember({"bash", "zsh"}));
  add_completion_words_command(*cmd, global, exit_code);
  cmd->require_subcommand(0, 1);
  // The callback holds `shell`: the option writes into it when the command line is parsed.
  cmd->callback([&app, &exit_code, shell, cmd] {
    if (!cmd->get_subcommands().empty())
      return; // `completion words` ran
    if (shell->empty()) {
      fmt::print(stderr, "rsca completion: which shell? bash or zsh\n");
      exit_code = kUsage;
      return;
    }
    fmt::print("{}", *shell == "zsh" ? zsh_script(app) : bash_script(app));
    exit_code = kOk;
  });
}

} // namespace rsca::cli
