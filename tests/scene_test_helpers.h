// What the scene-format tests share: the check that a bad scene is one InputError line naming its place.
#pragma once

#include <gtest/gtest.h>

#include <string>

#include "accel/core/error.h"
#include "tracer/scene.h"

namespace ab::test {

/// Expects parse_scene(xml) as bad.xml to throw one InputError line "bad.xml:LINE: ..." holding words.
inline void expect_scene_error(const std::string& xml, int line, const std::string& words) {
  try {
    parse_scene(xml, "bad.xml", ".");
    ADD_FAILURE() << "no error for: " << xml;
  } catch (const InputError& e) {
    const std::string msg = e.what();
    EXPECT_EQ(msg.rfind("bad.xml:" + std::to_string(line) + ": ", 0), 0u) << msg;
    EXPECT_NE(msg.find(words), std::string::npos) << msg;
    EXPECT_EQ(msg.find('\n'), std::string::npos) << msg;
  }
}

}  // namespace ab::test
