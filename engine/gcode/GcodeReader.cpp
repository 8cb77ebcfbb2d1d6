#include "engine/gcode/GcodeReader.h"

#include "engine/gcode/GcodeError.h"
#include "engine/gcode/Interpreter.h"

#include <string>
#include <vector>

namespace engage {
Toolpath readProgram(const std::string& path, const ReaderOptions& options) {
  return readProgramText(gcode::readFile(path), path, options);
}

Toolpath readPrograms(const std::vector<std::string>& paths, const ReaderOptions& options) {
  Toolpath all;
  ReaderOptions o = options;
  for (const std::string& path : paths) {
    Toolpath one = readProgram(path, o);
    const int files = static_cast<int>(all.files.size());
    const int blocks = static_cast<int>(all.blocks.size());
    if (all.moves.size() + one.moves.size() > options.maxMoves)
      throw GcodeError(path, 1, 1,
                       "expected at most " + std::to_string(options.maxMoves) +
                           " moves in the programs together" + options.maxMovesWhy +
                           ", found more");
    // The first program is taken whole (not copied: a long program's moves are a large share
    // of the run's heap), the others appended.
    for (ToolLoad l : one.toolLoads) {
      l.file += files;
      l.firstMove += all.moves.size();
      all.toolLoads.push_back(l);
    }
    if (all.moves.empty() && all.blocks.empty()) {
      all.moves = std::move(one.moves);
      all.blocks = std::move(one.blocks);
    } else {
      all.moves.reserve(all.moves.size() + one.moves.size());
      for (Move& m : one.moves) {
        m.file += files;
        m.block += blocks;
        all.moves.push_back(std::move(m));
      }
      all.blocks.reserve(all.blocks.size() + one.blocks.size());
      for (SourceBlock& b : one.blocks) {
        b.file += files;
        all.blocks.push_back(std::move(b));
      }
    }
    for (Toolpath::InertCode c : one.inert) {
      c.file += files;
      all.inert.push_back(c);
    }
    for (Toolpath::Place c : one.unoffsetCompensation) {
      c.file += files;
      all.unoffsetCompensation.push_back(c);
    }
    all.files.insert(all.files.end(), one.files.begin(), one.files.end());
    all.inch = one.inch;
    all.unitsSet = all.unitsSet || one.unitsSet;
    if (all.latheLine == 0 && one.latheLine != 0) {
      all.latheLine = one.latheLine;
      all.lathe = one.lathe;
    }
    if (!all.moves.empty()) {
      o.start = all.moves.back().end;
      o.startTool = all.moves.back().tool;
      o.startKnown = true;
    }
  }
  return all;
}

Toolpath readProgramText(const std::string& text, const std::string& name,
                         const ReaderOptions& options) {
  gcode::Interpreter interpreter(options);
  return interpreter.run(gcode::makeSource(name, text));
}

}  // namespace engage
