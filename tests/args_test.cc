// util/args: sizes, counts, numbers and lists, and the splitting of argv.
#include "util/args.h"

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "test_util.h"

namespace weaver {
namespace {

uint64_t parsed_size(const std::string& text) {
  uint64_t v = 0;
  const Status st = parse_bytes(text, "--memory", &v);
  EXPECT_TRUE(st.ok()) << text << ": " << st.message();
  return v;
}

uint64_t count_of(const std::string& text) {
  uint64_t v = 0;
  const Status st = parse_count(text, "--max-elements", &v);
  EXPECT_TRUE(st.ok()) << text << ": " << st.message();
  return v;
}

TEST(ArgsTest, SizesArePowersOf1024WithOptionalBOrIB) {
  EXPECT_EQ(parsed_size("1048576"), 1048576u);
  EXPECT_EQ(parsed_size("512K"), 512u << 10);
  EXPECT_EQ(parsed_size("256M"), 256u << 20);
  EXPECT_EQ(parsed_size("256m"), 256u << 20);
  EXPECT_EQ(parsed_size("2G"), 2ull << 30);
  EXPECT_EQ(parsed_size("2GB"), 2ull << 30);
  EXPECT_EQ(parsed_size("2GiB"), 2ull << 30);
  EXPECT_EQ(parsed_size("3T"), 3ull << 40);
  EXPECT_EQ(parsed_size("1.5M"), 3u << 19);
  EXPECT_EQ(parsed_size("100B"), 100u);
  EXPECT_EQ(parsed_size("15999999T"), 15999999ull << 40);  // just below 2^64
}

TEST(ArgsTest, BadOrHugeSizesAreRefusedNamingTheOption) {
  for (const std::string bad : {"", "M", "-1", "12X", "1MM", "1 M", "0x10", "1e3", "256MiBs"}) {
    uint64_t v = 0;
    const Status st = parse_bytes(bad, "--memory", &v);
    EXPECT_EQ(st.code(), Status::Code::kInvalidArgument) << "'" << bad << "'";
    EXPECT_NE(st.message().find("--memory"), std::string::npos) << st.message();
  }
  for (const std::string huge : {"16777216T", "18446744073709551616", "99999999999999999999G"}) {
    uint64_t v = 7;
    const Status st = parse_bytes(huge, "--memory", &v);
    EXPECT_NE(st.message().find("too large"), std::string::npos) << huge << ": " << st.message();
    EXPECT_EQ(v, 7u);  // untouched: never wrapped
  }
}

TEST(ArgsTest, CountsArePowersOf1000) {
  EXPECT_EQ(count_of("5000000"), 5000000u);
  EXPECT_EQ(count_of("5K"), 5000u);
  EXPECT_EQ(count_of("5M"), 5000000u);
  EXPECT_EQ(count_of("5G"), 5000000000u);
  EXPECT_EQ(count_of("2T"), 2000000000000u);
  EXPECT_EQ(count_of("1.5G"), 1500000000u);
  uint64_t v = 0;
  EXPECT_FALSE(parse_count("5GB", "--max-elements", &v).ok());  // bytes only for sizes
  EXPECT_FALSE(parse_count("20000000T", "--max-elements", &v).ok());
}

TEST(ArgsTest, IntegersNumbersAndLists) {
  uint64_t u = 0;
  ASSERT_OK(parse_u64("18446744073709551615", "N", &u));
  EXPECT_EQ(u, UINT64_MAX);
  EXPECT_FALSE(parse_u64("18446744073709551616", "N", &u).ok());
  EXPECT_FALSE(parse_u64("-3", "N", &u).ok());
  EXPECT_FALSE(parse_u64("3 ", "N", &u).ok());
  EXPECT_FALSE(parse_u64("", "N", &u).ok());
  double d = 0;
  ASSERT_OK(parse_double("-2.5e3", "F", &d));
  EXPECT_EQ(d, -2500);
  EXPECT_FALSE(parse_double("inf", "F", &d).ok());
  EXPECT_FALSE(parse_double("nan", "F", &d).ok());
  EXPECT_FALSE(parse_double("1.0x", "F", &d).ok());
  std::vector<uint64_t> list;
  ASSERT_OK(parse_u64_list("1,2,3", "--blocks", 3, &list));
  EXPECT_EQ(list, (std::vector<uint64_t>{1, 2, 3}));
  const Status st = parse_u64_list("1,2", "--blocks", 3, &list);
  EXPECT_NE(st.message().find("needs 3 comma-separated values"), std::string::npos);
  EXPECT_FALSE(parse_u64_list("1,,3", "--blocks", 3, &list).ok());
  std::vector<double> dl;
  ASSERT_OK(parse_double_list("1e5,2.5,0", "--domain", 3, &dl));
  EXPECT_EQ(dl, (std::vector<double>{1e5, 2.5, 0}));
}

Status parse(std::vector<std::string> words, ParsedArgs* out) {
  std::vector<char*> argv;
  for (std::string& w : words) argv.push_back(w.data());
  return parse_args(static_cast<int>(argv.size()), argv.data(), 2, {"memory", "threads"}, {"json"},
                    out);
}

TEST(ArgsTest, ArgvSplitsIntoPositionalsValuesAndFlags) {
  ParsedArgs a;
  ASSERT_OK(parse({"weaver", "extract", "db", "--memory", "1G", "--json", "more"}, &a));
  EXPECT_EQ(a.positional, (std::vector<std::string>{"db", "more"}));
  EXPECT_EQ(a.values.at("memory"), "1G");
  EXPECT_TRUE(a.flags.count("json"));
  EXPECT_TRUE(a.has("memory"));
  EXPECT_FALSE(a.has("threads"));
  EXPECT_FALSE(a.help);
  ParsedArgs h;
  ASSERT_OK(parse({"weaver", "extract", "-h"}, &h));
  EXPECT_TRUE(h.help);
  const std::vector<std::pair<std::vector<std::string>, std::string>> bad = {
      {{"weaver", "extract", "--memory", "1G", "--memory", "2G"}, "given twice"},
      {{"weaver", "extract", "--json", "--json"}, "given twice"},
      {{"weaver", "extract", "--memory"}, "needs a value"},
      {{"weaver", "extract", "--colour"}, "unknown option --colour"},
  };
  for (const auto& [words, message] : bad) {
    ParsedArgs p;
    const Status st = parse(words, &p);
    EXPECT_NE(st.message().find(message), std::string::npos) << st.message();
  }
}

}  // namespace
}  // namespace weaver
