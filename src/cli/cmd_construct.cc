#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>

#include "cli/cli.h"
#include "construct/construct.h"
#include "construct/estimate.h"
#include "model/geo_frame.h"
#include "modeldb/open_model.h"
#include "util/progress.h"

namespace weaver::cli {
namespace {

constexpr char kUsage[] =
    "usage: weaver construct DB --model NAME [--grid FILE] [--freq F] [--ppw N]\n"
    "                           [--vs-min V] [--domain LX,LY,LZ] [--min-level L]\n"
    "                           [--max-level L] [--max-elements N] [--memory BYTES]\n"
    "                           [--threads N] [--origin-geo LON,LAT [--azimuth DEG]\n"
    "                           [--utm-zone Z]] [--outside clamp|error] [--plain]\n"
    "                           [--surface SOURCE [--surface-crs frame|lonlat]]\n"
    "                           [--top-elevation E] [--model-z depth|elevation]\n"
    "                           [--surface-edge M] [--unbalanced] [--quiet]\n"
    "\n"
    "Builds the octant table of DB from a velocity model: every leaf satisfies\n"
    "edge <= Vs_min / (F * N), Vs_min being the least Vs of the model over 27\n"
    "sample points of the leaf (corners, edge midpoints, face centres, centre),\n"
    "and no leaf is finer than needed; then the octree is 2:1 balanced (face and\n"
    "edge), each subtree in memory as it is descended: the table is the one\n"
    "'weaver construct --unbalanced' then 'weaver balance' write.  New leaves\n"
    "of the balance carry their own material.  Leaves carry Vp, Vs and density (and Qp,\n"
    "Qs where the model has them) at their centre.  The domain (metres; x, y\n"
    "horizontal, z depth) is made a union of blocks: 100000,100000,37500 is\n"
    "8 x 8 x 3 blocks of level 3; 100000,80000,37500 is 40 x 32 x 15 blocks of\n"
    "2500 m in a root of 64 (160 km).  A domain no blocks tile exactly (up to\n"
    "1024 along its longest side) is rounded up to blocks of 1/128 of that side.\n"
    "  --model NAME       halfspace, loh1, basin (a synthetic sedimentary basin),\n"
    "                     grid (with --grid FILE; format in src/model/grid_model.h,\n"
    "                     read whole), db:MODEL.db (a model database, 'weaver model\n"
    "                     import'), or a model file imported into DB's own model\n"
    "                     table first: etree:FILE, grid:FILE, layers:FILE, xyz:FILE\n"
    "                     (formats in 'weaver model --help'); rfile:FILE, an SW4\n"
    "                     rfile, sampled as SW4 does and bringing its topography;\n"
    "                     a model read from storage is sampled within --memory\n"
    "                     whatever its size\n"
    "  --freq F           highest frequency to resolve, Hz (default 0.5)\n"
    "  --ppw N            points per wavelength (default 10)\n"
    "  --vs-min V         Vs floor in the rule, m/s (default none)\n"
    "  --domain LX,LY,LZ  metres (default 100000,100000,37500)\n"
    "  --origin-geo LON,LAT  where the domain's origin (x = y = 0) lies, WGS84\n"
    "                     degrees: exports add longitude and latitude, queries take\n"
    "                     --geo; default: the model's own, when it has one\n"
    "  --azimuth DEG      of the x axis, clockwise from north (default 0: x north,\n"
    "                     y east, z down); a transverse Mercator about the origin\n"
    "  --utm-zone Z[s]    project by UTM zone Z instead ('s': southern)\n"
    "  --outside clamp|error  where the domain reaches past a model database's\n"
    "                     box: take the nearest model cell's values (clamp, the\n"
    "                     default, said in the plan) or refuse to start (error)\n"
    "  --min-level L, --max-level L   bounds on leaf levels (default 0, 20)\n" WEAVER_GROUND_USAGE
    "  --max-elements N   refuse to start when a coarse sampling of the model\n"
    "                     estimates more leaves than N (default 5G), or more\n"
    "                     disk than is free; the estimate is printed first\n"
    "  --threads N        worker threads, each descending its own subtrees\n"
    "                     (default: the number of cores); the table is the same\n"
    "                     for every N\n"
    "  --memory BYTES     memory budget (default 256M): the octant table's cache\n"
    "                     and the leaves of subtrees visited ahead of the writer\n"
    "  --plain            write plain leaf pages (default: packed, where keys are\n"
    "                     delta-coded and payload fields stored column-wise)\n"
    "  --unbalanced       write the descent's leaves unbalanced (for 'weaver\n"
    "                     balance', or to compare)\n"
    "  --quiet            no progress line on stderr (default: one that updates\n"
    "                     itself on a terminal, a line every 10 s otherwise; its\n"
    "                     percent is the share of the printed estimate that lies\n"
    "                     before the last leaf written, in Z-order)\n";

}  // namespace

// --origin-geo LON,LAT, --azimuth DEG, --utm-zone ZONE[s]: the frame's
// text form (model/geo_frame.h), checked; "" without --origin-geo.
Status geo_options(const ParsedArgs& args, std::string* geo) {
  const bool origin = args.values.count("origin-geo") != 0;
  if (!origin) {
    if (args.values.count("azimuth") || args.values.count("utm-zone")) {
      return Status::InvalidArgument("--azimuth and --utm-zone need --origin-geo LON,LAT");
    }
    return Status::Ok();
  }
  std::string text = args.values.at("origin-geo");
  if (args.values.count("azimuth")) {
    double az = 0;
    WEAVER_RETURN_IF_ERROR(parse_double(args.values.at("azimuth"), "--azimuth", &az));
    text += "," + args.values.at("azimuth");
  }
  if (args.values.count("utm-zone")) text += ",utm" + args.values.at("utm-zone");
  GeoFrame g;
  WEAVER_RETURN_IF_ERROR(GeoFrame::parse(text, &g));
  *geo = g.to_text();
  return Status::Ok();
}

// --surface, --surface-crs, --top-elevation, --model-z, --surface-edge.
Status ground_options(const ParsedArgs& args, ConstructOptions* o) {
  const auto value = [&](const char* name) -> const std::string* {
    auto it = args.values.find(name);
    return it == args.values.end() ? nullptr : &it->second;
  };
  if (const std::string* v = value("surface")) {
    SurfaceSource s;
    WEAVER_RETURN_IF_ERROR(parse_surface_source(*v, &s));
    o->surface = *v;
  }
  if (const std::string* v = value("surface-crs")) {
    if (*v != "frame" && *v != "lonlat")
      return Status::InvalidArgument("--surface-crs '" + *v + "': frame or lonlat");
    if (*v == "lonlat" && o->geo.empty() && !value("origin-geo"))
      return Status::InvalidArgument("--surface-crs lonlat needs --origin-geo LON,LAT");
    o->surface_crs = *v == "lonlat" ? SurfaceCrs::kLonLat : SurfaceCrs::kFrame;
  }
  if (const std::string* v = value("top-elevation")) {
    WEAVER_RETURN_IF_ERROR(parse_double(*v, "--top-elevation", &o->top_elevation));
  }
  if (const std::string* v = value("model-z")) {
    ModelZ z;
    WEAVER_RETURN_IF_ERROR(parse_model_z(*v, &z));
    o->model_z = *v;
  }
  if (const std::string* v = value("surface-edge")) {
    WEAVER_RETURN_IF_ERROR(parse_double(*v, "--surface-edge", &o->surface_edge_m));
    if (!(o->surface_edge_m > 0)) return Status::InvalidArgument("--surface-edge must be positive");
  }
  return Status::Ok();
}

Status parse_construct_options(const ParsedArgs& args, ConstructOptions* o) {
  auto number = [&](const char* name, double* v) -> Status {
    if (!args.values.count(name)) return Status::Ok();
    return parse_double(args.values.at(name), std::string("--") + name, v);
  };
  auto level = [&](const char* name, int* v) -> Status {
    if (!args.values.count(name)) return Status::Ok();
    uint64_t l = 0;
    WEAVER_RETURN_IF_ERROR(parse_u64(args.values.at(name), std::string("--") + name, &l));
    if (l > 20) return Status::InvalidArgument(std::string("--") + name + " must be 0..20");
    *v = static_cast<int>(l);
    return Status::Ok();
  };
  if (!args.values.count("model")) return Status::InvalidArgument("--model NAME is required");
  o->packed = !args.flags.count("plain");
  o->balanced = !args.flags.count("unbalanced");
  o->model = args.values.at("model");
  if (args.values.count("grid")) o->grid_file = args.values.at("grid");
  WEAVER_RETURN_IF_ERROR(number("freq", &o->freq));
  WEAVER_RETURN_IF_ERROR(number("ppw", &o->ppw));
  WEAVER_RETURN_IF_ERROR(number("vs-min", &o->vs_min));
  WEAVER_RETURN_IF_ERROR(level("min-level", &o->min_level));
  WEAVER_RETURN_IF_ERROR(level("max-level", &o->max_level));
  if (args.values.count("max-elements")) {
    WEAVER_RETURN_IF_ERROR(
        parse_count(args.values.at("max-elements"), "--max-elements", &o->max_elements));
  }
  if (args.values.count("domain")) {
    std::vector<double> d;
    WEAVER_RETURN_IF_ERROR(parse_double_list(args.values.at("domain"), "--domain", 3, &d));
    o->domain_m = {d[0], d[1], d[2]};
  }
  WEAVER_RETURN_IF_ERROR(geo_options(args, &o->geo));
  WEAVER_RETURN_IF_ERROR(outside_option(args, &o->outside_error));
  WEAVER_RETURN_IF_ERROR(ground_options(args, o));
  return memory_option(args, &o->memory);
}

Status import_model_option(const std::string& db, ConstructOptions* o) {
  if (!is_model_source(o->model)) return Status::Ok();
  const std::string from = o->model;
  ModelImportResult r;
  WEAVER_RETURN_IF_ERROR(import_model_source(db, o->memory, &o->model, &r));
  std::printf("imported   %s: %llu read, %llu octants in %s's model table\n", from.c_str(),
              (unsigned long long)r.read, (unsigned long long)r.octants, db.c_str());
  return Status::Ok();
}

void print_construct_plan(const ConstructOptions& o, const ConstructPlan& p,
                          const std::string& db) {
  std::printf("model      %s\n", p.model.c_str());
  std::printf("rule       edge <= Vs_min / (%g Hz x %g ppw)%s\n", o.freq, o.ppw,
              o.vs_min > 0 ? (", Vs floor " + std::to_string(int(o.vs_min)) + " m/s").c_str() : "");
  std::printf("domain     %g x %g x %g m = %u x %u x %u blocks of level %d (%g m)%s\n",
              p.domain_m[0], p.domain_m[1], p.domain_m[2], p.blocks[0], p.blocks[1], p.blocks[2],
              p.block_level, p.root_edge_m / (1 << p.block_level),
              p.rounded_up ? ", rounded up to whole blocks" : "");
  std::printf("root       %g m, tick %.6g m, levels %d..%d\n", p.root_edge_m, p.tick_m,
              std::max(o.min_level, p.block_level), o.max_level);
  if (!o.geo.empty()) std::printf("geo        origin lon,lat,azimuth %s\n", o.geo.c_str());
  if (!p.outside.empty()) {
    std::printf("outside    %s: points there take the nearest model cell's values\n",
                p.outside.c_str());
  }
  if (p.carved) {
    std::printf(
        "ground     %s: %g to %g m; top (z = 0) at elevation %g m; the model read by %s%s\n",
        p.surface_source.c_str(), p.surface->lowest(), p.surface->highest(), p.ground.top_elevation,
        model_z_name(p.ground.model_z),
        p.ground.model_z == ModelZ::kDepth ? " below the ground" : " (down from sea level)");
  } else if (p.ground.top_elevation != 0) {
    std::printf("ground     flat at elevation %g m; the model read by %s\n", p.ground.top_elevation,
                model_z_name(p.ground.model_z));
  }
  if (!p.surface_outside.empty()) std::printf("surface    %s\n", p.surface_outside.c_str());
  std::printf(
      "estimate   about %.3g elements, %.3g to %.3g GB of disk (a coarse sampling of the model; "
      "the less where neighbouring leaves share their materials)\n",
      p.estimated_elements, p.estimated_least_disk_bytes / 1e9, p.estimated_disk_bytes / 1e9);
  const double free = free_disk_bytes(db);
  if (free >= 0 && free < p.estimated_disk_bytes) {
    std::printf(
        "disk       %.3g GB free: enough only if the materials pack well; a run that fills "
        "the disk fails and leaves no partial table\n",
        free / 1e9);
  }
}

int parse_construct_command(int argc, char** argv, std::string* db, ConstructOptions* o,
                            bool* quiet) {
  ParsedArgs args;
  Status st = parse_args(argc, argv, 2,
                         {"model",   "grid",        "freq",          "ppw",      "vs-min",
                          "domain",  "min-level",   "max-level",     "memory",   "max-elements",
                          "threads", "origin-geo",  "azimuth",       "utm-zone", "outside",
                          "surface", "surface-crs", "top-elevation", "model-z",  "surface-edge"},
                         {"plain", "quiet", "unbalanced"}, &args);
  if (args.help) return std::fputs(kUsage, stdout), 0;
  if (!st.ok()) return usage_error("construct", st.message(), kUsage);
  if (args.positional.size() != 1) return usage_error("construct", "expected one DB", kUsage);
  st = parse_construct_options(args, o);
  if (st.ok()) st = threads_option(args, default_threads(), &o->threads);
  if (!st.ok()) return usage_error("construct", st.message(), kUsage);
  *db = args.positional[0];
  *quiet = args.flags.count("quiet") != 0;
  return -1;
}

int cmd_construct(int argc, char** argv) {
  std::string db;
  ConstructOptions o;
  bool quiet = false;
  const int parsed = parse_construct_command(argc, argv, &db, &o, &quiet);
  if (parsed >= 0) return parsed;
  Status st = import_model_option(db, &o);
  if (!st.ok()) return report("construct", st);
  ConstructPlan plan;
  st = plan_construct(o, &plan);
  if (st.is_invalid_argument()) return usage_error("construct", st.message(), kUsage);
  if (!st.ok()) return report("construct", st);
  print_construct_plan(o, plan, db);
  std::fflush(stdout);
  const auto t0 = std::chrono::steady_clock::now();
  ProgressLine line(ProgressLine::style_for_stderr(quiet), "construct", "leaves");
  o.progress = line.fn();
  ConstructResult r;
  st = construct_octree(db, o, &plan, &r);
  line.finish();
  if (!st.ok()) return report("construct", st);
  print_construct_result(
      r, std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  return 0;
}

void print_construct_result(const ConstructResult& r, double secs) {
  std::printf(
      "constructed %llu leaves in %.2fs (%.0f leaves/s), edges %g..%g m, deepest level "
      "%d, worst %.2f points per wavelength, %.2f bytes/leaf\n",
      (unsigned long long)r.elements, secs, r.elements / secs, r.smallest_edge_m, r.largest_edge_m,
      finest_level(r.levels), r.worst_ppw, double(r.table_bytes) / r.elements);
  if (r.elements > 0 && r.least_dt < HUGE_VAL) {
    std::printf(
        "time step  least edge / vp %.6g s, at element %llu (an explicit solver's step is "
        "a Courant number times it)\n",
        r.least_dt, (unsigned long long)r.least_dt_element);
  }
  print_construct_balance(r);
}

void print_construct_balance(const ConstructResult& r) {
  if (r.descended == 0) return;  // unbalanced
  std::printf(
      "balanced   %llu leaves descended, %llu more made by the balance's splits; %llu "
      "leaves around the subtrees descended again (%.1f%%)\n",
      (unsigned long long)r.descended, (unsigned long long)(r.elements + r.air - r.descended),
      (unsigned long long)r.neighbours, 100.0 * r.neighbours / std::max<uint64_t>(1, r.descended));
  if (r.air > 0 || r.cut > 0) {
    std::printf(
        "carved     %llu leaves of air cut away, %llu elements cut by "
        "the ground (solid fraction below 1)\n",
        (unsigned long long)r.air, (unsigned long long)r.cut);
  }
}

}  // namespace weaver::cli
