/* locate_points DB < points: the C API answering "x y z" lines (ticks) with
 * "x y z element level vs", or "x y z outside". */
#include <stdio.h>
#include <weaver/weaver_c.h>

int main(int argc, char** argv) {
  char error[256];
  unsigned x, y, z;
  if (argc != 2) {
    fprintf(stderr, "usage: locate_points DB < points\n");
    return 2;
  }
  weaver_db* db = weaver_open(argv[1], 0, error, sizeof error);
  if (db == NULL) {
    fprintf(stderr, "locate_points: %s\n", error);
    return 1;
  }
  while (scanf("%u %u %u", &x, &y, &z) == 3) {
    const uint32_t xyz[3] = {x, y, z};
    weaver_hit hit;
    if (weaver_locate(db, xyz, 1, &hit) != 0) {
      fprintf(stderr, "locate_points: %s\n", weaver_last_error(db));
      weaver_close(db);
      return 1;
    }
    if (hit.inside) {
      printf("%u %u %u %llu %d %g\n", x, y, z, (unsigned long long)hit.element, hit.level, hit.vs);
    } else {
      printf("%u %u %u outside\n", x, y, z);
    }
  }
  weaver_close(db);
  return 0;
}
