#include <cstdio>

#include "cli/cli.h"
#include "db/output_path.h"
#include "gen/octree_gen.h"
#include "import/octant_text.h"

namespace weaver::cli {
namespace {

constexpr char kUsage[] =
    "usage: weaver generate FILE [--kind random|uniform|sphere|points] [--leaves N] [--level L]\n"
    "                            [--max-level L] [--blocks BX,BY,BZ] [--block-level L]\n"
    "                            [--radius R] [--points N] [--seed S] [--shuffle]\n"
    "\n"
    "Writes a sample octree as octant text ('x y z level' per line, ticks).\n"
    "The domain is BX x BY x BZ blocks of level --block-level (default 1,1,1 at 0:\n"
    "the whole root); e.g. --blocks 8,8,3 --block-level 3 is 100 x 100 x 37.5 km\n"
    "when the root is 100 km.\n"
    "  --kind random   split random leaves until there are at least --leaves\n"
    "                  (default 100000), none finer than --max-level (default 20)\n"
    "  --kind uniform  every leaf at --level (default 6)\n"
    "  --kind sphere   graded: octants within 2 edges of a sphere of radius 0.3 x\n"
    "                  root are refined from --level down to --max-level; 2:1\n"
    "                  balanced by construction; --radius R (default 0.3) sets\n"
    "                  the sphere's radius as a fraction of the root edge\n"
    "  --kind points   the same rule around --points N random points (default\n"
    "                  1000): scattered refinement, also 2:1 balanced\n"
    "  --shuffle       write the leaves in random order instead of key order\n";

}  // namespace

int cmd_generate(int argc, char** argv) {
  ParsedArgs args;
  Status st = parse_args(
      argc, argv, 2,
      {"kind", "leaves", "level", "max-level", "blocks", "block-level", "seed", "radius", "points"},
      {"shuffle"}, &args);
  if (args.help) return std::fputs(kUsage, stdout), 0;
  if (!st.ok()) return usage_error("generate", st.message(), kUsage);
  if (args.positional.size() != 1) return usage_error("generate", "expected one FILE", kUsage);
  GenOptions o;
  uint64_t v = 0;
  if (args.values.count("kind")) {
    const std::string& k = args.values["kind"];
    if (k == "uniform") {
      o.kind = GenOptions::Kind::kUniform;
    } else if (k == "sphere") {
      o.kind = GenOptions::Kind::kSphere;
    } else if (k == "points") {
      o.kind = GenOptions::Kind::kPoints;
    } else if (k != "random") {
      return usage_error("generate", "--kind must be random, uniform, sphere or points", kUsage);
    }
  }
  auto number = [&](const char* name, uint64_t max, auto* field) -> Status {
    if (!args.values.count(name)) return Status::Ok();
    WEAVER_RETURN_IF_ERROR(parse_u64(args.values[name], std::string("--") + name, &v));
    if (v > max) return Status::InvalidArgument(std::string("--") + name + " is too large");
    *field = static_cast<std::remove_reference_t<decltype(*field)>>(v);
    return Status::Ok();
  };
  if (st.ok()) st = number("leaves", uint64_t{1} << 31, &o.leaves);
  if (st.ok()) st = number("level", kMaxLevel, &o.level);
  if (st.ok()) st = number("max-level", kMaxLevel, &o.max_level);
  if (st.ok()) st = number("block-level", kMaxLevel, &o.block_level);
  if (st.ok()) st = number("seed", UINT64_MAX, &o.seed);
  if (st.ok()) st = number("points", uint64_t{1} << 24, &o.points);
  if (st.ok() && args.values.count("blocks")) {
    std::vector<uint64_t> b;
    st = parse_u64_list(args.values["blocks"], "--blocks", 3, &b);
    for (size_t a = 0; st.ok() && a < 3; ++a)
      o.blocks[a] = static_cast<uint32_t>(std::min<uint64_t>(b[a], UINT32_MAX));
  }
  if (st.ok() && args.values.count("radius")) {
    st = parse_double(args.values["radius"], "--radius", &o.radius);
  }
  o.shuffle = args.flags.count("shuffle") != 0;
  if (st.ok()) st = check_output_path(args.positional[0]);
  if (!st.ok()) return usage_error("generate", st.message(), kUsage);
  std::vector<Octant> leaves;
  st = generate_octree(o, &leaves);
  if (st.is_invalid_argument()) return usage_error("generate", st.message(), kUsage);
  if (st.ok()) st = write_octant_text(args.positional[0], leaves, "weaver sample octree");
  if (!st.ok()) return report("generate", st);
  std::printf("wrote %zu leaves to %s\n", leaves.size(), args.positional[0].c_str());
  return 0;
}

}  // namespace weaver::cli
