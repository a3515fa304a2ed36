/* Writes the etree test fixtures with the original etree library
 * (SCECcode/euclid-etree, libsrc), and records what the library itself
 * answers about them.  Not part of weaver: it is built by hand against that
 * library, as tests/data/etree/README.md says.
 *
 *   make_fixtures OUTDIR
 *
 * writes, for each of cmu and usgs:
 *   OUTDIR/<name>.e          the etree file
 *   OUTDIR/<name>.octants    every octant the library's cursor returns, in
 *                            order: "x y z level type values..." (type L/I)
 *   OUTDIR/<name>.search     etree_search at random pixels: "px py pz ->
 *                            x y z level values..." as the library answered
 */
#include <fcntl.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "etree.h"

#define MAX_LEVEL 12
#define MAX_OCTANTS 20000

typedef struct {
  float vp, vs, rho;
} cmu_t;

typedef struct {
  float vp, vs, rho, qp, qs, depth;
  int16_t block, zone;
} usgs_t;

typedef struct {
  etree_addr_t addr;
  usgs_t v;
} node_t;

static uint64_t rng = 88172645463325252ull;
static double uniform(void) {
  rng ^= rng << 13;
  rng ^= rng >> 7;
  rng ^= rng << 17;
  return (rng >> 11) * (1.0 / 9007199254740992.0);
}

static node_t nodes[MAX_OCTANTS]; /* preorder: interior before its children */
static int node_count = 0;

static usgs_t material(etree_tick_t x, etree_tick_t y, etree_tick_t z) {
  usgs_t v;
  const double depth = z / 2147483648.0;
  v.vs = (float)(300 + 3000 * depth + 400 * uniform());
  v.vp = (float)(v.vs * (1.7 + 0.2 * uniform()));
  v.rho = (float)(1800 + 0.3 * v.vs);
  v.qp = (float)(v.vs / 10 + 20);
  v.qs = (float)(v.vs / 20 + 10);
  v.depth = (float)(depth * 37500);
  v.block = (int16_t)(1 + (x >> 29));
  v.zone = (int16_t)(1 + (y >> 29));
  return v;
}

/* A random subtree below `a`; `fill`, when not null, is the one value every
 * leaf below takes (a uniform region, which a reader may merge). */
static usgs_t grow(etree_addr_t a, const usgs_t* fill) {
  const int me = node_count++;
  nodes[me].addr = a;
  double split = a.level < 2 ? 1.0 : 0.62 - 0.035 * a.level;
  if (a.level >= MAX_LEVEL || node_count + 8 >= MAX_OCTANTS / 2) split = 0;
  if (uniform() >= split) {
    nodes[me].addr.type = ETREE_LEAF;
    nodes[me].v = fill ? *fill : material(a.x, a.y, a.z);
    return nodes[me].v;
  }
  nodes[me].addr.type = ETREE_INTERIOR;
  usgs_t uni = material(a.x, a.y, a.z);
  const usgs_t* child_fill = fill ? fill : (uniform() < 0.2 ? &uni : NULL);
  const etree_tick_t half = (etree_tick_t)1 << (31 - a.level - 1);
  usgs_t mean;
  memset(&mean, 0, sizeof mean);
  for (int c = 0; c < 8; ++c) {
    etree_addr_t k = a;
    k.level = a.level + 1;
    k.x += (c & 1) ? half : 0;
    k.y += (c & 2) ? half : 0;
    k.z += (c & 4) ? half : 0;
    usgs_t v = grow(k, child_fill);
    mean.vp += v.vp / 8, mean.vs += v.vs / 8, mean.rho += v.rho / 8;
    mean.qp += v.qp / 8, mean.qs += v.qs / 8, mean.depth += v.depth / 8;
  }
  mean.block = -999; /* as the USGS file marks interior octants */
  mean.zone = -999;
  nodes[me].v = mean;
  return mean;
}

static void fail(etree_t* ep, const char* what) {
  fprintf(stderr, "%s: %s\n", what, ep ? etree_strerror(etree_errno(ep)) : "");
  exit(1);
}

static void print_values(FILE* f, const usgs_t* v, int usgs) {
  fprintf(f, " %.9g %.9g %.9g", v->vp, v->vs, v->rho);
  if (usgs) fprintf(f, " %.9g %.9g %.9g %d %d", v->qp, v->qs, v->depth, v->block, v->zone);
}

static void record(const char* dir, const char* name, int usgs) {
  char path[1024];
  snprintf(path, sizeof path, "%s/%s.e", dir, name);
  etree_t* ep = etree_open(path, O_RDONLY, 0, 0, 3);
  if (!ep) fail(NULL, "reopen");
  snprintf(path, sizeof path, "%s/%s.octants", dir, name);
  FILE* f = fopen(path, "w");
  etree_addr_t root;
  memset(&root, 0, sizeof root);
  if (etree_initcursor(ep, root) != 0) fail(ep, "initcursor");
  do {
    etree_addr_t a;
    usgs_t v;
    memset(&v, 0, sizeof v);
    if (etree_getcursor(ep, &a, NULL, &v) != 0) fail(ep, "getcursor");
    fprintf(f, "%u %u %u %d %c", a.x, a.y, a.z, a.level, a.type == ETREE_LEAF ? 'L' : 'I');
    print_values(f, &v, usgs);
    fputc('\n', f);
  } while (etree_advcursor(ep) == 0);
  fclose(f);
  snprintf(path, sizeof path, "%s/%s.search", dir, name);
  f = fopen(path, "w");
  for (int i = 0; i < 2000; ++i) {
    etree_addr_t q, hit;
    memset(&q, 0, sizeof q);
    q.x = (etree_tick_t)(uniform() * 2147483648.0);
    q.y = (etree_tick_t)(uniform() * 2147483648.0);
    q.z = (etree_tick_t)(uniform() * 2147483648.0);
    q.level = ETREE_MAXLEVEL;
    q.type = ETREE_LEAF;
    usgs_t v;
    memset(&v, 0, sizeof v);
    if (etree_search(ep, q, &hit, NULL, &v) != 0) fail(ep, "search");
    fprintf(f, "%u %u %u -> %u %u %u %d", q.x, q.y, q.z, hit.x, hit.y, hit.z, hit.level);
    print_values(f, &v, usgs);
    fputc('\n', f);
  }
  fclose(f);
  etree_close(ep);
}

int main(int argc, char** argv) {
  if (argc != 2) {
    fprintf(stderr, "usage: make_fixtures OUTDIR\n");
    return 2;
  }
  char path[1024];
  etree_addr_t root;
  memset(&root, 0, sizeof root);

  /* cmu.e: createcvm's schema and UCVM's CMU metadata; leaves only, inserted
   * in a shuffled order so that the B-tree splits pages as it grows. */
  node_count = 0;
  grow(root, NULL);
  snprintf(path, sizeof path, "%s/cmu.e", argv[1]);
  etree_t* ep = etree_open(path, O_CREAT | O_TRUNC | O_RDWR, 1, 0, 3);
  if (!ep) fail(NULL, "open cmu");
  if (etree_registerschema(ep, "float Vp; float Vs; float density;") != 0) fail(ep, "schema");
  int order[MAX_OCTANTS];
  for (int i = 0; i < node_count; ++i) order[i] = i;
  for (int i = node_count - 1; i > 0; --i) {
    int j = (int)(uniform() * (i + 1));
    int t = order[i];
    order[i] = order[j], order[j] = t;
  }
  int leaves = 0;
  for (int i = 0; i < node_count; ++i) {
    const node_t* n = &nodes[order[i]];
    if (n->addr.type != ETREE_LEAF) continue;
    cmu_t v = {n->v.vp, n->v.vs, n->v.rho};
    if (etree_insert(ep, n->addr, &v) != 0) fail(ep, "insert");
    ++leaves;
  }
  if (etree_setappmeta(ep,
                       "Title:weaver_fixture Author:make_fixtures Date:2026-11-24 3 "
                       "Vp(float);Vs(float);density(float) 33.580000 -118.700000 "
                       "100000.000000 100000.000000 0.000000 100000.000000 "
                       "2147483648 2147483648 2147483648") != 0)
    fail(ep, "appmeta");
  if (etree_close(ep) != 0) fail(NULL, "close cmu");
  fprintf(stderr, "cmu.e: %d leaves\n", leaves);
  record(argv[1], "cmu", 0);

  /* usgs.e: the USGS Bay Area schema, every octant (interior ones hold the
   * mean of their children), written by sorted append. */
  node_count = 0;
  grow(root, NULL);
  snprintf(path, sizeof path, "%s/usgs.e", argv[1]);
  ep = etree_open(path, O_CREAT | O_TRUNC | O_RDWR, 1, 0, 3);
  if (!ep) fail(NULL, "open usgs");
  if (etree_registerschema(ep,
                           "float32_t Vp; float32_t Vs; float32_t Density; float32_t Qp; "
                           "float32_t Qs; float32_t DepthFreeSurf; int16_t FaultBlock; "
                           "int16_t Zone;") != 0)
    fail(ep, "schema");
  if (etree_beginappend(ep, 1.0) != 0) fail(ep, "beginappend");
  for (int i = 0; i < node_count; ++i) {
    if (etree_append(ep, nodes[i].addr, &nodes[i].v) != 0) fail(ep, "append");
  }
  if (etree_endappend(ep) != 0) fail(ep, "endappend");
  if (etree_setappmeta(ep,
                       "SCEC_CVM_V1|weaver fixture|make_fixtures|2026-11-24|200.0|1.0|10.0|"
                       "vp,float,4,m/s;vs,float,4,m/s;rho,float,4,kg/m^3|"
                       "+proj=utm +zone=10 +datum=WGS84|-123.0,35.0,0.0|35.0|"
                       "100000.0,100000.0,100000.0|2147483648,2147483648,2147483648") != 0)
    fail(ep, "appmeta");
  if (etree_close(ep) != 0) fail(NULL, "close usgs");
  fprintf(stderr, "usgs.e: %d octants\n", node_count);
  record(argv[1], "usgs", 1);

  /* tiny.e: the seed of the etree_file fuzz target (fuzz/corpus): the root,
   * its 8 children and their 64, every one stored, appended depth-first
   * (a parent before its children, the library's key order). */
  snprintf(path, sizeof path, "%s/tiny.e", argv[1]);
  ep = etree_open(path, O_CREAT | O_TRUNC | O_RDWR, 1, 0, 3);
  if (!ep) fail(NULL, "open tiny");
  if (etree_registerschema(ep, "float Vp; float Vs; float density;") != 0) fail(ep, "schema");
  if (etree_beginappend(ep, 1.0) != 0) fail(ep, "beginappend");
  {
    etree_addr_t a;
    memset(&a, 0, sizeof a);
    a.type = ETREE_INTERIOR;
    cmu_t v = {2000, 1000, 2100};
    if (etree_append(ep, a, &v) != 0) fail(ep, "append");
    for (int c = 0; c < 8; ++c) {
      const etree_tick_t h = (etree_tick_t)1 << 30, q = (etree_tick_t)1 << 29;
      a.level = 1, a.type = ETREE_INTERIOR;
      a.x = (c & 1) * h, a.y = ((c >> 1) & 1) * h, a.z = ((c >> 2) & 1) * h;
      v.vs = (float)(500 + 100 * c);
      if (etree_append(ep, a, &v) != 0) fail(ep, "append");
      etree_addr_t b = a;
      for (int g = 0; g < 8; ++g) {
        b.level = 2, b.type = ETREE_LEAF;
        b.x = a.x + (g & 1) * q, b.y = a.y + ((g >> 1) & 1) * q, b.z = a.z + ((g >> 2) & 1) * q;
        cmu_t w = {v.vp, v.vs + 10 * g, v.rho};
        if (etree_append(ep, b, &w) != 0) fail(ep, "append");
      }
    }
  }
  if (etree_endappend(ep) != 0) fail(ep, "endappend");
  if (etree_setappmeta(ep, "Title:tiny Author:make_fixtures Date:2026-11-25 3 "
                           "Vp(float);Vs(float);density(float) 33.58 -118.7 "
                           "100000.0 100000.0 0.0 100000.0 2147483648 2147483648 2147483648") != 0)
    fail(ep, "appmeta");
  if (etree_close(ep) != 0) fail(NULL, "close tiny");
  return 0;
}
