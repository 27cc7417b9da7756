#include "cli_suggest.h"

#include <cstdlib>
#include <string>
#include <vector>

#include "absl/strings/str_cat.h"
#include "tactforce/io/suggest.h"

namespace tactforce::cli {
namespace {

std::vector<std::string> FlagNames(const CLI::App& app) {
  std::vector<std::string> names;
  for (const CLI::Option* option : app.get_options()) {
    for (const std::string& name : option->get_lnames()) names.push_back("--" + name);
    for (const std::string& name : option->get_snames()) names.push_back("-" + name);
  }
  return names;
}

std::vector<const CLI::App*> Subcommands(const CLI::App& app) {
  return app.get_subcommands([](const CLI::App*) { return true; });
}

const CLI::Option* FindFlag(const CLI::App& app, const std::string& flag) {
  for (const CLI::Option* option : app.get_options()) {
    if (option->check_name(flag)) return option;
  }
  return nullptr;
}

const CLI::App* FindSubcommand(const CLI::App& app, const std::string& word) {
  for (const CLI::App* sub : Subcommands(app)) {
    if (sub->check_name(word)) return sub;
  }
  return nullptr;
}

bool IsNumber(const std::string& token) {
  char* end = nullptr;
  std::strtod(token.c_str(), &end);
  return end != token.c_str() && *end == '\0';
}

// A flag token's name: "--plot=x.svg" -> "--plot", "-n20" -> "-n" when "-n" exists.
std::string FlagName(const CLI::App& app, const std::string& token) {
  std::string flag = token.substr(0, token.find('='));
  if (token[1] != '-' && flag.size() > 2 && FindFlag(app, flag) == nullptr)
    flag = flag.substr(0, 2);
  return flag;
}

std::string UnknownFlag(const std::string& flag, const CLI::App& app, const std::string& path) {
  const std::vector<std::string> near = io::NearestNames(flag, FlagNames(app));
  std::string message = absl::StrCat("unknown flag '", flag, "' for '", path, "'");
  if (!near.empty()) absl::StrAppend(&message, io::DidYouMean(flag, near));
  return message;
}

}  // namespace

ArgumentHint HintForArguments(const CLI::App& app, int argc, const char* const* argv) {
  const CLI::App* current = &app;
  std::string path = app.get_name();
  for (int i = 1; i < argc; ++i) {
    const std::string token = argv[i];
    if (token == "--") break;
    if (token.size() > 1 && token[0] == '-' && !IsNumber(token)) {
      const std::string flag = FlagName(*current, token);
      const CLI::Option* option = FindFlag(*current, flag);
      if (option == nullptr) return {UnknownFlag(flag, *current, path), path};
      const bool value_attached =
          token.find('=') != std::string::npos || flag.size() < token.size();
      if (!value_attached && option->get_type_size_min() > 0 && option->get_expected_min() > 0) ++i;
      continue;
    }
    if (const CLI::App* sub = FindSubcommand(*current, token)) {
      current = sub;
      absl::StrAppend(&path, " ", sub->get_name());
      continue;
    }
    std::vector<std::string> commands;
    for (const CLI::App* sub : Subcommands(*current)) commands.push_back(sub->get_name());
    if (!commands.empty() && current->get_require_subcommand_min() > 0) {
      return {absl::StrCat("unknown command '", token, "' for '", path, "'",
                           io::DidYouMean(token, commands)),
              path};
    }
  }
  return {"", path};
}

}  // namespace tactforce::cli
