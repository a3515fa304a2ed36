#include <algorithm>
#include <cstdio>
#include <vector>

#include "cli/cli.h"
#include "db/output_path.h"
#include "slice/slice.h"

namespace weaver::cli {
namespace {

constexpr char kUsage[] =
    "usage: weaver slice DB --at COORD --out FILE.png|FILE.svg [--axis x|y|z] [--units ticks|m]\n"
    "                    [--color level|vp|vs|rho] [--width PIXELS] [--region A0,B0,A1,B1]\n"
    "                    [--danglings] [--z domain|elevation]\n"
    "\n"
    "A picture of the mesh cut by the plane AXIS = COORD: the elements the plane\n"
    "cuts, outlined and filled by a field on a colour scale (viridis), with a colour\n"
    "bar and axes in km (m for small meshes). PNG or SVG by the name of --out, written\n"
    "whole or not at all.\n"
    "  --axis x|y|z       the plane's normal (default z: a map view; x or y: sections)\n"
    "  --at COORD         where the plane crosses the axis, in ticks, or metres with\n"
    "                     --units m; an element holds corner <= p < corner + edge\n"
    "  --z domain|elevation  a z plane's --at as the domain's depth (default) or as\n"
    "                     an elevation in metres up (a mesh built with --surface:\n"
    "                     z = its top's elevation minus --at; implies --units m)\n"
    "  --color FIELD      level (default), or vp, vs, rho for a mesh built from a model\n"
    "  --width PIXELS     the picture's width (default 1600; 200 to 20000); the height\n"
    "                     follows the section's shape\n"
    "  --region A0,B0,A1,B1  only this part of the plane, on its two axes in order\n"
    "                     (x,y for --axis z; y,z for x; x,z for y), in --at's units\n"
    "  --danglings        mark the dangling nodes that lie on the plane (edge-dangling\n"
    "                     red, face-dangling white); only a plane on element faces has\n"
    "                     nodes on it\n"
    "  --memory BYTES     memory budget (default 256M): the table caches; the picture\n"
    "                     takes width x height x 3 bytes more\n"
    "\n"
    "example: weaver slice basin.db --axis z --at 1000 --units m --color vs --out vs.png\n";

}  // namespace

int cmd_slice(int argc, char** argv) {
  ParsedArgs args;
  Status st = parse_args(argc, argv, 2,
                         {"axis", "at", "units", "out", "color", "width", "region", "memory", "z"},
                         {"danglings", "quiet"}, &args);
  if (args.help) return std::fputs(kUsage, stdout), 0;
  if (!st.ok()) return usage_error("slice", st.message(), kUsage);
  if (args.positional.size() != 1) return usage_error("slice", "expected DB", kUsage);
  if (!args.values.count("at") || !args.values.count("out")) {
    return usage_error("slice", "--at and --out are required", kUsage);
  }
  SliceOptions o;
  const std::string axis = args.values.count("axis") ? args.values.at("axis") : "z";
  const std::string units = args.values.count("units") ? args.values.at("units") : "ticks";
  if (axis != "x" && axis != "y" && axis != "z")
    st = Status::InvalidArgument("--axis is x, y or z");
  if (st.ok() && units != "ticks" && units != "m")
    st = Status::InvalidArgument("--units is ticks or m");
  o.axis = axis[0] - 'x';
  o.at_is_ticks = units == "ticks";
  if (st.ok() && args.values.count("z")) {
    const std::string& z = args.values.at("z");
    if (z != "domain" && z != "elevation")
      st = Status::InvalidArgument("--z is domain or elevation");
    o.at_is_elevation = z == "elevation";
    if (o.at_is_elevation) o.at_is_ticks = false;
  }
  if (st.ok()) st = parse_double(args.values.at("at"), "--at", &o.at_m);
  if (st.ok() && args.values.count("color")) o.color = args.values.at("color");
  uint64_t width = uint64_t(o.width);
  if (st.ok() && args.values.count("width"))
    st = parse_u64(args.values.at("width"), "--width", &width);
  o.width = int(std::min<uint64_t>(width, 1 << 30));
  if (st.ok() && (o.width < 200 || o.width > 20000))
    st = Status::InvalidArgument("--width must be 200 to 20000");
  const std::string& out = args.values.at("out");
  const bool image = out.size() >= 4 && (out.compare(out.size() - 4, 4, ".png") == 0 ||
                                         out.compare(out.size() - 4, 4, ".svg") == 0);
  if (st.ok()) st = check_output_path(out);
  if (st.ok() && !image) st = Status::InvalidArgument("--out must end in .png or .svg");
  o.danglings = args.flags.count("danglings") != 0;
  if (st.ok() && args.values.count("region")) {
    std::vector<double> r;
    st = parse_double_list(args.values.at("region"), "--region", 4, &r);
    if (st.ok()) std::copy(r.begin(), r.end(), o.region), o.has_region = true;
  }
  if (st.ok()) st = memory_option(args, &o.memory);
  if (!st.ok()) return usage_error("slice", st.message(), kUsage);
  SliceResult r;
  st = render_slice(args.positional[0], o, args.values.at("out"), &r);
  if (!st.ok()) return report("slice", st);
  if (!args.flags.count("quiet")) {
    std::printf("wrote %s: %d x %d pixels, %llu elements cut at %c = %u ticks, %s %g to %g",
                args.values.at("out").c_str(), r.width, r.height, (unsigned long long)r.elements,
                "xyz"[o.axis], r.at_ticks, o.color.c_str(), r.min, r.max);
    if (o.danglings) std::printf(", %llu dangling nodes marked", (unsigned long long)r.danglings);
    std::printf("\n");
  }
  return 0;
}

}  // namespace weaver::cli
