// A question of the JSON API as the service hands it to the query engine:
// every value parsed and bounded by the service first (serve/params.h).
// Nothing here is a client's string, so nothing a client sends can become
// an option, a word of a command line or a path: the command line's
// runner (cli/cmd_serve.cc) builds the query from these typed fields.
#pragma once

#include <cstdint>

namespace weaver::serve {

struct ApiQuery {
  enum class Kind {
    kLocate,
    kMaterial,
    kNodeAt,
    kElement,
    kNode,
    kNeighbors,
    kNodeElements,
    kDepends,
    kRange,
  };
  Kind kind = Kind::kLocate;
  // locate, material, node-at: the points of the request's body, not point.
  bool batch = false;
  // A batch's points answered at a time (0: the Explorer's): set when the
  // service lends the batch its lane of memory (Service::run_batch).
  size_t batch_points = 0;
  // One point: metres when metres or geo (lon, lat, depth), else whole ticks.
  double point[3] = {0, 0, 0};
  uint64_t id = 0;                     // element, node, neighbors, ...
  double box[6] = {0, 0, 0, 0, 0, 0};  // range: metres, or whole ticks
  bool metres = false;                 // coordinates in and out in metres
  bool geo = false;                    // points as lon, lat, depth
  // What a point's z is (?z_mode=): 0 domain (depth below the top), 1
  // elevation, 2 depth below the local ground; 1 and 2 are metres.
  int z_mode = 0;
  unsigned neighbor_kinds = 0;  // bit 0 faces, 1 edges, 2 corners; 0: faces
  // range: list the leaves, a page of them (list_from, at most list_limit);
  // the runner sets *list_next and *list_count.
  bool list = false;
  uint64_t list_from = 0, list_limit = 0;
  uint64_t* list_next = nullptr;
  uint64_t* list_count = nullptr;
};

}  // namespace weaver::serve
