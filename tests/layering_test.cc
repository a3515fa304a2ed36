// The include graph follows the layering of README.md and src/README.md:
// schema <- storage <- src, and inside src only the edges src/README.md
// allows.  Reads the sources (WEAVER_SOURCE_DIR).
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <set>
#include <string>

namespace weaver {
namespace {

namespace fs = std::filesystem;

// The folder an include or a file belongs to: "schema", "storage", or a
// folder of src ("db", "extract", ...).
std::string layer_of(const std::string& path) { return path.substr(0, path.find('/')); }

// Every (file, included project folder) in dir.
std::multimap<std::string, std::string> includes_under(const fs::path& dir) {
  static const std::regex include_re("^#include \"([a-z_]+/[^\"]+)\"");
  std::multimap<std::string, std::string> out;
  for (const auto& entry : fs::recursive_directory_iterator(dir)) {
    const std::string ext = entry.path().extension().string();
    if (ext != ".h" && ext != ".cc") continue;
    std::ifstream in(entry.path());
    std::string line;
    std::smatch m;
    while (std::getline(in, line)) {
      if (std::regex_search(line, m, include_re)) {
        out.emplace(fs::relative(entry.path(), dir).string(), layer_of(m[1].str()));
      }
    }
  }
  return out;
}

const fs::path kRoot = WEAVER_SOURCE_DIR;

TEST(LayeringTest, SchemaAndStorageIncludeNothingAbove) {
  for (const auto& [file, to] : includes_under(kRoot / "schema")) {
    EXPECT_EQ(to, "schema") << "schema/" << file;
  }
  for (const auto& [file, to] : includes_under(kRoot / "storage")) {
    EXPECT_TRUE(to == "schema" || to == "storage") << "storage/" << file << " includes " << to;
  }
}

TEST(LayeringTest, SrcFoldersIncludeOnlyWhatSrcReadmeAllows) {
  const std::set<std::string> base = {"schema", "util"};
  const std::set<std::string> engine = {"schema", "storage", "util"};
  const std::set<std::string> stage = {"schema", "storage", "util", "db", "sort", "model"};
  std::map<std::string, std::set<std::string>> allowed = {
      {"util", base},       {"model", base},     {"gen", base},        {"sort", engine},
      {"db", engine},       {"import", stage},   {"construct", stage}, {"balance", stage},
      {"extract", stage},   {"export", stage},   {"query", stage},     {"verify", stage},
      {"partition", stage}, {"boundary", stage},
  };
  allowed["verify"].insert({"balance", "query", "boundary", "extract"});
  allowed["mesh"] = {"schema", "storage", "util", "db"};
  allowed["modeldb"] = {"schema", "storage", "util", "db", "model"};
  for (const char* s : {"construct", "query", "balance", "verify"}) allowed[s].insert("modeldb");
  for (const char* s : {"export", "query", "partition", "boundary"}) allowed[s].insert("mesh");
  // slice draws what query finds and writes through export's OutputFile.
  allowed["slice"] = stage;
  allowed["slice"].insert({"mesh", "query", "export"});
  // serve answers over HTTP what query finds, draws tiles as slice does, and
  // hands out regions as export writes them.
  allowed["serve"] = stage;
  allowed["serve"].insert({"mesh", "query", "slice", "export"});
  int checked = 0;
  for (const auto& [file, to] : includes_under(kRoot / "src")) {
    const std::string from = layer_of(file);
    // The command lines (weaver's, weaver-mpi's) and the API use anything.
    if (from == "cli" || from == "mpi" || from == "api") continue;
    ASSERT_TRUE(allowed.count(from)) << "src/" << from << "/ is not in src/README.md's table";
    EXPECT_TRUE(to == from || allowed[from].count(to))
        << "src/" << file << " includes " << to << "/, which src/README.md does not allow";
    ++checked;
  }
  EXPECT_GT(checked, 100);
}

}  // namespace
}  // namespace weaver
