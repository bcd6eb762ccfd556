#include "exporters/obj_sequence_writer.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <set>

#include "core/error.hpp"
#include "core/text.hpp"
#include "exporters/texcoord_table.hpp"
#include "output/atomic_file.hpp"
#include "output/finite_values.hpp"
#include "output/version.hpp"

namespace softbake {

namespace {

// Room for any line this file formats: three shortest-form doubles are at most 3·24 characters,
// and an "f" line three triples of 20-digit indices.
constexpr std::size_t kMaxLine = 256;

// More than any number needs: 24 characters for the longest shortest-form double.
constexpr std::size_t kMaxNumber = 32;

// std::to_chars without a format is the shortest text that reads back to the same value, is
// locale-independent and never allocates: the reason OBJ formatting is fast and exact.
template <class Number>
char* putNumber(char* out, Number value) {
  return std::to_chars(out, out + kMaxNumber, value).ptr;
}

char* putText(char* out, std::string_view text) {
  for (char c : text) *out++ = c;
  return out;
}

void appendLine(std::string& buffer, const char* begin, const char* end) {
  buffer.append(begin, std::size_t(end - begin));
}

/// "v x y z\n" or "vn x y z\n".
template <class Vector>
void appendVectorLine(std::string& buffer, std::string_view statement, const Vector& v) {
  char line[kMaxLine];
  char* p = putText(line, statement);
  p = putNumber(p, v.x());
  *p++ = ' ';
  p = putNumber(p, v.y());
  *p++ = ' ';
  p = putNumber(p, v.z());
  *p++ = '\n';
  appendLine(buffer, line, p);
}

// OBJ and MTL statements end at whitespace, so a name with spaces would lose its tail; duplicate
// names would share one material. Both are made harmless here, keeping names readable.
std::vector<std::string> objectNames(const std::vector<Body>& bodies) {
  std::vector<std::string> names;
  std::set<std::string> used;
  for (std::size_t i = 0; i < bodies.size(); ++i) {
    std::string name = bodies[i].name.empty() ? cat("body", i + 1) : bodies[i].name;
    for (char& c : name)
      if (static_cast<unsigned char>(c) <= ' ' || c == '#') c = '_';
    std::string unique = name;
    for (int n = 2; !used.insert(unique).second; ++n) unique = cat(name, "_", n);
    names.push_back(std::move(unique));
  }
  return names;
}

// Evenly spread hues (golden-ratio steps) at a soft saturation: neighbouring bodies differ
// clearly and none is garish in a viewport.
Vec3f bodyColour(std::size_t index) {
  const float hue = std::fmod(0.08f + 0.618034f * float(index), 1.0f) * 6;
  const float saturation = 0.5f, value = 0.85f;
  const int sector = int(hue);
  const float f = hue - float(sector);
  const float p = value * (1 - saturation), q = value * (1 - saturation * f),
              t = value * (1 - saturation * (1 - f));
  switch (sector) {
    case 0:
      return {value, t, p};
    case 1:
      return {q, value, p};
    case 2:
      return {p, value, t};
    case 3:
      return {p, q, value};
    case 4:
      return {t, p, value};
    default:
      return {value, p, q};
  }
}

std::string materialLibrary(const std::vector<std::string>& names, const std::string& scene,
                            const std::vector<Vec3f>& colors) {
  std::string text = cat("# softbake ", softbakeVersion(), " materials of scene ", scene, "\n");
  for (std::size_t i = 0; i < names.size(); ++i) {
    char line[kMaxLine];
    char* p = putText(line, "Kd");
    const bool given = i < colors.size() && colors[i].x() >= 0;
    const Vec3f colour = given ? colors[i] : bodyColour(i);
    for (float channel : {colour.x(), colour.y(), colour.z()}) {
      *p++ = ' ';
      p = std::to_chars(p, p + kMaxNumber, channel, std::chars_format::fixed, 3).ptr;
    }
    *p++ = '\n';
    text += cat("\nnewmtl ", names[i], "\n");
    appendLine(text, line, p);
    text += "Ka 0 0 0\nKs 0.1 0.1 0.1\nNs 32\nd 1\nillum 2\n";
  }
  return text;
}

std::string texcoordLines(const TexcoordTable& table) {
  std::string text;
  text.reserve(table.uvs.size() * 24);
  for (const Vec2f& uv : table.uvs) {
    char line[kMaxLine];
    char* p = putText(line, "vt ");
    p = putNumber(p, uv.x());
    *p++ = ' ';
    p = putNumber(p, uv.y());
    *p++ = '\n';
    appendLine(text, line, p);
  }
  return text;
}

// `firstTexcoord` is the 1-based OBJ index of the body's first vt.
std::string faceLines(const SceneTopology& topology, const Body& body, const std::string& material,
                      const TexcoordTable& texcoords, std::uint64_t firstTexcoord) {
  std::string text = cat("usemtl ", material, "\ns 1\n");
  const bool hasUvs = !texcoords.uvs.empty();
  text.reserve(text.size() + std::size_t(body.triangleCount) * (hasUvs ? 40 : 30));
  for (Index t = 0; t < body.triangleCount; ++t) {
    const Triangle& triangle = topology.triangles[body.firstTriangle + t];
    char line[kMaxLine];
    char* p = putText(line, "f");
    for (int corner = 0; corner < 3; ++corner) {
      // Particles are numbered globally in the scene as in the file, so v and vn share the index.
      char index[kMaxNumber];
      char* const indexEnd = putNumber(index, std::uint64_t(triangle[corner]) + 1);
      *p++ = ' ';
      p = putText(p, std::string_view(index, std::size_t(indexEnd - index)));
      *p++ = '/';
      if (hasUvs) p = putNumber(p, firstTexcoord + texcoords.corners[t][corner]);
      *p++ = '/';
      p = putText(p, std::string_view(index, std::size_t(indexEnd - index)));
    }
    *p++ = '\n';
    appendLine(text, line, p);
  }
  return text;
}

// A vt index out of range would make the whole file unreadable for most importers.
void checkRenderMesh(const Body& body) {
  const RenderMesh& render = body.render;
  if (render.uvs.empty()) return;
  if (render.renderTriangles.size() != body.triangleCount)
    throw Error(cat("body '", body.name, "': ", render.renderTriangles.size(),
                    " render triangles for ", body.triangleCount, " triangles"));
  for (const Triangle& triangle : render.renderTriangles)
    for (Index v : triangle)
      if (v >= render.uvs.size())
        throw Error(cat("body '", body.name, "': render vertex ", v, " is beyond its ",
                        render.uvs.size(), " UVs"));
}

// The scene name is a file name stem and the `mtllib` argument, where whitespace separates
// several libraries.
void checkScene(const std::string& scene) {
  const bool usable = !scene.empty() && scene != "." && scene != ".." &&
                      std::none_of(scene.begin(), scene.end(), [](char c) {
                        return c == '/' || static_cast<unsigned char>(c) <= ' ';
                      });
  if (!usable)
    throw Error(cat("scene name '", scene,
                    "' cannot name OBJ files: it must be non-empty, without '/' or spaces"));
}

}  // namespace

ObjSequenceWriter::ObjSequenceWriter(std::shared_ptr<const SceneTopology> topology,
                                     const std::filesystem::path& outputDirectory,
                                     std::string scene, int framePadding,
                                     std::vector<Vec3f> bodyColors)
    : topology_(std::move(topology)),
      particleCount_(topology_->particleCount()),
      objDirectory_(outputDirectory / "obj"),
      scene_(std::move(scene)),
      framePadding_(framePadding) {
  checkScene(scene_);
  if (framePadding < 1 || framePadding > 9)
    throw Error(cat("frame padding must be 1 to 9 digits, not ", framePadding));
  const std::vector<Body>& bodies = topology_->bodies;
  // Every frame repeats the UVs, so a bad one is refused before any frame: name them all.
  const std::filesystem::path frames = outputDirectory / naming().pattern();
  for (const Body& body : bodies) {
    checkRenderMesh(body);
    for (std::size_t v = 0; v < body.render.uvs.size(); ++v)
      requireFinite(frames, body.render.uvs[v],
                    [&] { return cat("body '", body.name, "': the UV of render vertex ", v); });
  }

  const std::vector<std::string> names = objectNames(bodies);
  std::uint64_t firstTexcoord = 1;
  for (std::size_t b = 0; b < bodies.size(); ++b) {
    const Body& body = bodies[b];
    const TexcoordTable texcoords = texcoordTable(body.render);
    text_.push_back({cat("o ", names[b], "\n"), texcoordLines(texcoords),
                     faceLines(*topology_, body, names[b], texcoords, firstTexcoord)});
    firstTexcoord += texcoords.uvs.size();
  }

  makeDirectories(objDirectory_);
  const std::string materials = materialLibrary(names, scene_, bodyColors);
  writeFileAtomically(materialLibraryPath(), materials);
  bytes_.store(materials.size(), std::memory_order_relaxed);
}

std::filesystem::path ObjSequenceWriter::framePath(int frameNumber) const {
  return objDirectory_ / naming().fileName(frameNumber);
}

FrameNaming ObjSequenceWriter::naming() const {
  return {"obj", scene_, ".obj", framePadding_};
}

std::filesystem::path ObjSequenceWriter::materialLibraryPath() const {
  return objDirectory_ / (scene_ + ".mtl");
}

OutputSequence ObjSequenceWriter::sequence() const {
  return {"obj", naming().pattern(), naming().printfPattern(), {cat("obj/", scene_, ".mtl")}};
}

void ObjSequenceWriter::write(const Frame& frame) {
  if (frame.positions.size() != particleCount_)
    throw Error(cat("frame ", frame.number, ": ", frame.positions.size(),
                    " particle positions for a scene of ", particleCount_));
  const std::filesystem::path path = framePath(frame.number);
  requireFinite(path, frame.time, [&] { return cat("frame ", frame.number, ": the time"); });
  buffer_.clear();
  pieces_.clear();
  char line[kMaxLine];
  char* p = putText(line, "# softbake ");
  p = putText(p, std::string_view(softbakeVersion()));
  p = putText(p, "\n# frame ");
  p = putNumber(p, frame.number);
  p = putText(p, ", time ");
  p = putNumber(p, frame.time);
  p = putText(p, " s\nmtllib ");
  appendLine(buffer_, line, p);
  buffer_ += scene_;
  buffer_ += ".mtl\n";
  addFormattedSince(0);

  for (std::size_t b = 0; b < text_.size(); ++b)
    formatBody(frame, topology_->bodies[b], text_[b], path);

  parts_.clear();
  std::uint64_t bytes = 0;
  for (const Piece& piece : pieces_) {
    parts_.push_back(piece.fixed
                         ? std::string_view(*piece.fixed)
                         : std::string_view(buffer_).substr(piece.begin, piece.end - piece.begin));
    bytes += parts_.back().size();
  }
  writeFileAtomically(path, parts_);
  bytes_.fetch_add(bytes, std::memory_order_relaxed);
}

void ObjSequenceWriter::formatBody(const Frame& frame, const Body& body, const BodyText& text,
                                   const std::filesystem::path& path) {
  addFixed(text.object);
  std::size_t begin = buffer_.size();
  const Vec3* const positions = frame.positions.data() + body.firstParticle;
  for (Index i = 0; i < body.particleCount; ++i) {
    const Vec3& v = positions[i];
    requireFinite(path, v, [&] {
      return cat("frame ", frame.number, ": body '", body.name, "': the position of particle ", i);
    });
    appendVectorLine(buffer_, "v ", v);
  }
  addFormattedSince(begin);
  addFixed(text.texcoords);

  begin = buffer_.size();
  computeBodyNormals(*topology_, frame.positions, body, normals_);
  for (std::size_t i = 0; i < normals_.size(); ++i) {
    requireFinite(path, normals_[i], [&] {
      return cat("frame ", frame.number, ": body '", body.name, "': the normal of particle ", i);
    });
    appendVectorLine(buffer_, "vn ", normals_[i]);
  }
  addFormattedSince(begin);
  addFixed(text.faces);
}

}  // namespace softbake
