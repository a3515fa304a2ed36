// A model database is named in the octant table's metadata by what it is
// (its source's file name and a digest of its pages), never by a path: the
// same model gives the same octant table in any directory, and balance finds
// the model for its split leaves by that name.
#include "modeldb/model_identity.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "balance/balance.h"
#include "construct/construct.h"
#include "db/database.h"
#include "modeldb/model_import.h"
#include "storage/btree.h"
#include "test_util.h"
#include "util/metadata_text.h"

namespace weaver {
namespace {

std::string fresh_dir(const std::string& name) {
  return testing::fresh_path("model_identity_" + name);
}

// A layered model with a soft top, written to dir/NAME and imported into a
// model database at `db`.
void layered_model_db(const std::string& dir, const std::string& db, double top_vs = 400) {
  std::filesystem::create_directories(dir);
  const std::string table = dir + "/hk.txt";
  std::ofstream(table) << "0 " << 2 * top_vs << " " << top_vs << " 1900\n"
                       << "700 5000 2900 2500\n"
                       << "2500 6000 3460 2700\n";
  ModelImportOptions o;
  o.from = "layers:" + table;
  ModelImportResult r;
  const Status st = import_model(db, o, &r);
  ASSERT_TRUE(st.ok()) << st.to_string();
}

std::string octant_file(const std::string& db) {
  std::unique_ptr<Database> d;
  EXPECT_TRUE(Database::open(db, Database::Mode::kRead, false, &d).ok());
  return d ? d->table_path("octants") : "";
}

std::string octant_metadata(const std::string& db) {
  std::unique_ptr<Database> d;
  EXPECT_TRUE(Database::open(db, Database::Mode::kRead, false, &d).ok());
  std::unique_ptr<BTree> t;
  EXPECT_TRUE(d->open_table("octants", 1 << 20, &t).ok());
  return t ? t->options().metadata : "";
}

ConstructOptions options_for(const std::string& model, bool balanced) {
  ConstructOptions o;
  o.model = model;
  o.freq = 1;
  o.domain_m = {4000, 4000, 3000};
  o.threads = 2;
  o.balanced = balanced;
  return o;
}

void construct(const std::string& db, const ConstructOptions& o) {
  ConstructPlan p;
  ConstructResult r;
  const Status st = construct_octree(db, o, &p, &r);
  ASSERT_TRUE(st.ok()) << st.to_string();
}

TEST(ModelIdentity, TheSameModelInTwoDirectoriesGivesTheSameOctantTable) {
  const std::string a = fresh_dir("a"), b = fresh_dir("b");
  layered_model_db(a, a + "/model.db");
  layered_model_db(b + "/elsewhere", b + "/other-name.db");
  std::string ida, idb;
  ASSERT_TRUE(model_table_identity(a + "/model.db", &ida).ok());
  ASSERT_TRUE(model_table_identity(b + "/other-name.db", &idb).ok());
  EXPECT_EQ(ida, idb);
  EXPECT_EQ(ida.rfind("layers:hk.txt#", 0), 0u) << ida;
  EXPECT_TRUE(is_model_identity(ida));
  EXPECT_FALSE(is_model_identity("db:" + a));
  EXPECT_FALSE(is_model_identity("basin"));

  construct(a + "/mesh.db", options_for("db:" + a + "/model.db", true));
  construct(b + "/mesh.db", options_for("db:" + b + "/other-name.db", true));
  EXPECT_EQ(metadata_item(octant_metadata(a + "/mesh.db"), "model"), ida);
  const std::string bytes_a = testing::slurp(octant_file(a + "/mesh.db"));
  EXPECT_FALSE(bytes_a.empty());
  EXPECT_EQ(bytes_a, testing::slurp(octant_file(b + "/mesh.db")));
  EXPECT_EQ(octant_metadata(a + "/mesh.db").find(a), std::string::npos);

  // Another model (a different soft top) has another identity.
  const std::string c = fresh_dir("c");
  layered_model_db(c, c + "/model.db", 500);
  std::string idc;
  ASSERT_TRUE(model_table_identity(c + "/model.db", &idc).ok());
  EXPECT_NE(idc, ida);
}

TEST(ModelIdentity, BalanceFindsTheModelByItsIdentityOrSaysWhichItNeeds) {
  const std::string dir = fresh_dir("balance");
  const std::string model = dir + "/model.db";
  layered_model_db(dir, model);
  construct(dir + "/onepass.db", options_for("db:" + model, true));
  construct(dir + "/twopass.db", options_for("db:" + model, false));
  const std::string before = testing::slurp(octant_file(dir + "/twopass.db"));

  // The mesh database has no model table of its own: balance cannot know
  // where the model is, and says so, leaving the table as it was.
  BalanceOptions blind;
  BalanceResult r;
  const Status st = balance_octree(dir + "/twopass.db", blind, &r);
  ASSERT_FALSE(st.ok());
  EXPECT_NE(st.message().find("--model db:PATH"), std::string::npos) << st.to_string();
  EXPECT_NE(st.message().find("layers:hk.txt#"), std::string::npos) << st.to_string();
  EXPECT_EQ(testing::slurp(octant_file(dir + "/twopass.db")), before);

  // A model database of another model is not taken for it.
  const std::string other = fresh_dir("other");
  layered_model_db(other, other + "/model.db", 500);
  BalanceOptions wrong;
  wrong.model_dirs = {other + "/model.db"};
  EXPECT_FALSE(balance_octree(dir + "/twopass.db", wrong, &r).ok());

  // Told where it is, balance splits leaves with the model's material: the
  // one-pass construct's table, byte for byte.
  BalanceOptions told;
  told.model_dirs = {model};
  const Status ok = balance_octree(dir + "/twopass.db", told, &r);
  ASSERT_TRUE(ok.ok()) << ok.to_string();
  EXPECT_GT(r.output_leaves, r.input_leaves);
  EXPECT_EQ(testing::slurp(octant_file(dir + "/twopass.db")),
            testing::slurp(octant_file(dir + "/onepass.db")));
}

TEST(ModelIdentity, AnImportedSourceIsFoundInTheMeshDatabaseItself) {
  // --model layers:FILE imports into the mesh database's own model table:
  // balance needs no --model there.
  const std::string dir = fresh_dir("own");
  std::filesystem::create_directories(dir);
  std::ofstream(dir + "/hk.txt") << "0 800 400 1900\n700 5000 2900 2500\n";
  for (const char* name : {"onepass.db", "twopass.db"}) {
    const std::string db = dir + "/" + name;
    ModelImportOptions io;
    io.from = "layers:" + dir + "/hk.txt";
    ModelImportResult ir;
    ASSERT_TRUE(import_model(db, io, &ir).ok());
    construct(db, options_for("db:" + db, std::string(name) == "onepass.db"));
  }
  BalanceOptions o;
  BalanceResult r;
  const Status st = balance_octree(dir + "/twopass.db", o, &r);
  ASSERT_TRUE(st.ok()) << st.to_string();
  EXPECT_EQ(testing::slurp(octant_file(dir + "/twopass.db")),
            testing::slurp(octant_file(dir + "/onepass.db")));
}

}  // namespace
}  // namespace weaver
