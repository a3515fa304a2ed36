#include "schema/record_schema.h"

#include <gtest/gtest.h>

namespace weaver {
namespace {

TEST(RecordSchema, ParsesPacksAndRoundTrips) {
  std::string error;
  auto s = RecordSchema::parse("vp:f32,vs:f32,rho:f32,tag:u8,id:i64", &error);
  ASSERT_TRUE(s) << error;
  EXPECT_EQ(s->record_size(), 4u + 4 + 4 + 1 + 8);
  EXPECT_EQ(s->find("id")->offset, 13u);
  EXPECT_EQ(s->to_text(), "vp:f32,vs:f32,rho:f32,tag:u8,id:i64");
  std::byte rec[21] = {};
  RecordSchema::set_double(rec, *s->find("vs"), 3464.5);
  RecordSchema::set_int(rec, *s->find("id"), -42);
  RecordSchema::set_int(rec, *s->find("tag"), 200);
  EXPECT_DOUBLE_EQ(RecordSchema::get_double(rec, *s->find("vs")), 3464.5);
  EXPECT_EQ(RecordSchema::get_int(rec, *s->find("id")), -42);
  EXPECT_EQ(RecordSchema::get_uint(rec, *s->find("tag")), 200u);
  EXPECT_EQ(static_cast<uint8_t>(rec[12]), 200);  // packed, no padding
}

TEST(RecordSchema, EmptyTextIsTheEmptySchema) {
  std::string error;
  auto s = RecordSchema::parse("", &error);
  ASSERT_TRUE(s);
  EXPECT_EQ(s->record_size(), 0u);
  EXPECT_TRUE(s->fields().empty());
}

TEST(RecordSchema, RejectsBadText) {
  std::string error;
  EXPECT_FALSE(RecordSchema::parse("vp", &error));
  EXPECT_NE(error.find("name:type"), std::string::npos);
  EXPECT_FALSE(RecordSchema::parse("vp:f16", &error));
  EXPECT_FALSE(RecordSchema::parse("1vp:f32", &error));
  EXPECT_FALSE(RecordSchema::parse("vp:f32,vp:f64", &error));
  EXPECT_NE(error.find("duplicate"), std::string::npos);
  EXPECT_FALSE(RecordSchema::parse("vp:f32,", &error));
}

}  // namespace
}  // namespace weaver
