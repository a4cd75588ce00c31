#include "base_connectivity.h"

#include <algorithm>
#include <array>
#include <cassert>
#include <string>

#include "isowave/core/error.h"
#include "isowave/core/mesh_topology.h"

namespace isowave::detail {
namespace {

constexpr std::uint32_t kNone = ~std::uint32_t{0};
// Far above any base mesh's face or hole, and small enough that corner
// counts stay in 32 bits.
constexpr std::uint64_t kMaxFaceSize = std::uint64_t{1} << 28;

// ------------------------------------------------------------ the border machine

// The kind of face that made a slot: the context of the face across it.
enum FaceKind : std::uint8_t { kTriangle, kQuad, kOtherPolygon, kHole, kFaceKinds };

FaceKind kind_of(std::uint32_t size, bool hole) {
  return hole ? kHole : size == 3 ? kTriangle : size == 4 ? kQuad : kOtherPolygon;
}

// A border slot: a half-edge of a processed face whose twin is unprocessed.
struct Slot {
  std::uint32_t vertex;       // its start vertex (canonical number)
  std::uint32_t next;         // the next slot along its border loop; kNone once consumed
  std::uint32_t prev;
  std::uint32_t consumed_by;  // the last face operation that consumed it
  std::uint32_t split_by;     // the last face operation that split the border at its start
  FaceKind owner;
};

// A run of the face's corners between the gate's chains: one new vertex, or
// an existing vertex z given by the slot starting at z that bounds the wedge
// the face lies in, followed by `chain` corners along border slots the face
// consumes (prev(slot), prev(prev(slot)), ...).
struct MiddleRun {
  std::uint32_t slot = kNone;  // kNone: a new vertex
  std::uint32_t chain = 0;
};

// A face attached at the gate slot u -> w, with corners [w, u, x_1 .. x_{size-2}].
struct FaceShape {
  std::uint32_t size = 0;
  bool hole = false;
  // Border slots consumed before the gate (x_1 -> u, x_2 -> x_1, ...); size - 1 closes the loop.
  std::uint32_t back = 0;
  // Border slots consumed after it (w -> x_{size-2}, ...); at most size - 2 - back.
  std::uint32_t forward = 0;
  // The size - 2 - back - forward corners between, in runs.
  std::vector<MiddleRun> middle;
};

// The border loops of the processed region, one loop per linked cycle of
// slots (flat arrays: a million faces make a few million slots). Encoder and
// decoder run the same machine, so both number vertices and slots alike.
class Border {
 public:
  std::uint32_t gate() const { return gate_; }
  std::uint32_t vertex_count() const { return static_cast<std::uint32_t>(faces_at_.size()); }
  std::uint32_t slot_count() const { return static_cast<std::uint32_t>(slots_.size()); }
  const Slot& slot(std::uint32_t s) const { return slots_[s]; }
  bool alive(std::uint32_t s) const { return s < slots_.size() && slots_[s].next != kNone; }
  // Faces processed around vertex v so far (holes included), at most kFacesAtCap.
  static constexpr int kFacesAtCap = 4;
  int faces_at(std::uint32_t v) const { return faces_at_[v]; }

  // A component's seed face of `size` new vertices; its slots are the border
  // and the first (from its first corner) the gate.
  void seed(std::uint32_t size, std::vector<std::uint32_t>& face) {
    face.clear();
    const std::uint32_t first = slot_count();
    for (std::uint32_t k = 0; k < size; ++k) {
      face.push_back(new_vertex());
      add_slot(face.back(), kind_of(size, false));
    }
    for (std::uint32_t k = 0; k < size; ++k) link(first + k, first + (k + 1) % size);
    count_face(face);
    gate_ = first;
  }

  // Attaches the face across the gate, writing its corners (gate order,
  // canonical numbers) to `face`; the gate moves on along the border, or to a
  // pending loop when this one closes (kNone when the component is done).
  // Returns nullptr, or what is impossible about the shape (a hostile stream).
  const char* attach(const FaceShape& shape, std::vector<std::uint32_t>& face) {
    ++operation_;
    const std::uint32_t g = gate_;
    consumed_.clear();
    consume(g);
    face.assign({slots_[slots_[g].next].vertex, slots_[g].vertex});
    std::uint32_t first = g;
    for (std::uint32_t i = 0; i < shape.back; ++i) {
      first = slots_[first].prev;
      if (!consume(first)) return "a face wraps around its border loop";
      if (i + 2 < shape.size) face.push_back(slots_[first].vertex);
    }
    if (shape.back + 1 == shape.size) {
      if (slots_[first].prev != g) return "a face closes a border loop of another length";
      finish(face);
      gate_ = pop_pending();
      return nullptr;
    }
    std::uint32_t last = g;
    forward_.clear();
    for (std::uint32_t j = 0; j < shape.forward; ++j) {
      last = slots_[last].next;
      if (!consume(last)) return "a face wraps around its border loop";
      forward_.push_back(slots_[slots_[last].next].vertex);
    }
    std::uint32_t corners = 2 + shape.back + shape.forward;
    for (const MiddleRun& run : shape.middle) corners += 1 + run.chain;
    if (corners != shape.size) return "a face of another size than stated";
    if (const char* problem = consume_middle(shape)) return problem;
    const std::uint32_t before = slots_[first].prev, after = slots_[last].next;
    if (slots_[before].consumed_by == operation_ || slots_[after].consumed_by == operation_)
      return "a face consumes its whole border loop and has more corners";
    link_path(shape, slots_[first].vertex, before, after, face);
    face.insert(face.end(), forward_.rbegin(), forward_.rend());
    finish(face);
    gate_ = after;
    return nullptr;
  }

 private:
  std::uint32_t new_vertex() {
    faces_at_.push_back(0);
    return vertex_count() - 1;
  }
  std::uint32_t add_slot(std::uint32_t vertex, FaceKind owner) {
    slots_.push_back({vertex, kNone, kNone, 0, 0, owner});
    return slot_count() - 1;
  }
  void link(std::uint32_t a, std::uint32_t b) {
    slots_[a].next = b;
    slots_[b].prev = a;
  }
  bool consume(std::uint32_t s) {
    if (!alive(s) || slots_[s].consumed_by == operation_) return false;
    slots_[s].consumed_by = operation_;
    consumed_.push_back(s);
    return true;
  }
  void count_face(const std::vector<std::uint32_t>& face) {
    for (std::uint32_t v : face)
      if (faces_at_[v] < kFacesAtCap) ++faces_at_[v];
  }

  // Consumes the chains of the middle runs, recording where each ends, and
  // checks that every slot the path will link to survives the operation
  // (so every live slot keeps live neighbours, whatever the stream says).
  const char* consume_middle(const FaceShape& shape) {
    run_ends_.clear();
    for (const MiddleRun& run : shape.middle) {
      if (run.slot == kNone) continue;
      if (!alive(run.slot) || slots_[run.slot].split_by == operation_) return "a face touches the border at an impossible place";
      slots_[run.slot].split_by = operation_;
      std::uint32_t end = run.slot;
      for (std::uint32_t i = 0; i < run.chain; ++i) {
        end = slots_[end].prev;
        if (!consume(end)) return "a face wraps around a border loop";
      }
      run_ends_.push_back(end);
    }
    std::size_t i = 0;
    for (const MiddleRun& run : shape.middle) {
      if (run.slot == kNone) continue;
      const std::uint32_t end = run_ends_[i++];
      if (slots_[run.slot].consumed_by == operation_ || slots_[slots_[end].prev].consumed_by == operation_)
        return "a face touches the border at an impossible place";
    }
    return nullptr;
  }

  // The face's new border half-edges from x_back through the middle corners to
  // the slot after the forward chain. At an existing vertex z the path turns
  // into z's old out-slot, and the in-slot before the run's chain continues
  // the path: the loop splits in two (or two loops merge); the part left
  // behind is pending.
  void link_path(const FaceShape& shape, std::uint32_t start_vertex, std::uint32_t before, std::uint32_t after,
                 std::vector<std::uint32_t>& face) {
    const FaceKind owner = kind_of(shape.size, shape.hole);
    std::uint32_t current = add_slot(start_vertex, owner);
    link(before, current);
    std::size_t i = 0;
    for (const MiddleRun& run : shape.middle) {
      if (run.slot == kNone) {
        face.push_back(new_vertex());
        const std::uint32_t next = add_slot(face.back(), owner);
        link(current, next);
        current = next;
        continue;
      }
      const std::uint32_t end = run_ends_[i++], in = slots_[end].prev;
      face.push_back(slots_[run.slot].vertex);
      for (std::uint32_t s = run.slot; s != end;) {
        s = slots_[s].prev;
        face.push_back(slots_[s].vertex);
      }
      const std::uint32_t next = add_slot(face.back(), owner);
      link(current, run.slot);
      pending_.push_back(current);
      link(in, next);
      current = next;
    }
    link(current, after);
  }

  void finish(const std::vector<std::uint32_t>& face) {
    for (std::uint32_t s : consumed_) slots_[s].next = slots_[s].prev = kNone;
    count_face(face);
  }

  std::uint32_t pop_pending() {
    while (!pending_.empty()) {
      const std::uint32_t s = pending_.back();
      pending_.pop_back();
      if (alive(s)) return s;
    }
    return kNone;
  }

  std::vector<Slot> slots_;
  std::vector<std::uint8_t> faces_at_;   // per vertex
  std::vector<std::uint32_t> pending_;   // a slot of every loop left behind by a split
  std::vector<std::uint32_t> consumed_;  // by the current operation
  std::vector<std::uint32_t> forward_;   // x_{size-2}, x_{size-3}, ... of the current operation
  std::vector<std::uint32_t> run_ends_;  // the last slot of each existing run's chain
  std::uint32_t gate_ = kNone;
  std::uint32_t operation_ = 0;
};

// ------------------------------------------------------------ symbols

// Split slots this close to the gate along the border are coded by their
// distance (the decoder walks at most this far per split).
constexpr int kNearBits = 4;
constexpr std::uint32_t kNearSlots = 1u << kNearBits;

// Adaptive contexts, fresh for every stream.
struct Models {
  Probability component = kProbabilityHalf;                 // another component follows
  std::array<Probability, kFaceKinds> hole{};                // by the gate owner's kind
  std::array<std::array<Probability, 8>, kFaceKinds + 1> size{};  // size - 3 (7 = escape) by owner kind; last: seeds
  IntegerModel large_size;                                   // size - 10 of a face of 10+ sides
  IntegerModel hole_size;                                    // size - 3 of a hole
  // A chain decision by chain (back, forward, middle), hole, and the faces already at its corner.
  std::array<std::array<std::array<Probability, Border::kFacesAtCap + 1>, 2>, 3> chain{};
  std::array<Probability, 2> existing{};                     // by hole
  Probability near = kProbabilityHalf;                       // the split slot is near the gate
  Probability near_backward = kProbabilityHalf;
  std::array<Probability, kNearSlots> near_distance{};       // distance - 1
  IntegerModel slot_age;                                     // else: slots made since the split slot
  Probability any_sharp = kProbabilityHalf;
  std::array<Probability, 2> sharp{};                        // by the previous vertex's flag

  Models() {
    hole.fill(kProbabilityHalf);
    for (auto& tree : size) tree.fill(kProbabilityHalf);
    for (auto& by_hole : chain)
      for (auto& row : by_hole) row.fill(kProbabilityHalf);
    existing.fill(kProbabilityHalf);
    near_distance.fill(kProbabilityHalf);
    sharp.fill(kProbabilityHalf);
  }
};

// The encoder and decoder share every symbol's code through a channel: the
// encoder's writes the value it is given (or nothing, when only ordering) and
// returns it, the decoder's ignores it and returns what it reads.
struct EncodeChannel {
  RangeEncoder* rc;
  int bit(Probability& p, int value) {
    if (rc) rc->encode_bit(p, value);
    return value;
  }
  std::int64_t integer(IntegerModel& m, std::int64_t value) {
    if (rc) encode_integer(*rc, m, value);
    return value;
  }
  bool exhausted() const { return false; }
};

struct DecodeChannel {
  RangeDecoder& rc;
  int bit(Probability& p, int) { return rc.decode_bit(p); }
  std::int64_t integer(IntegerModel& m, std::int64_t) { return decode_integer(rc, m); }
  bool exhausted() const { return rc.overran(); }
};

// A value below 2^Bits through an adaptive binary tree.
template <int Bits, typename Channel>
std::uint32_t code_tree(Channel& io, std::array<Probability, 1u << Bits>& tree, std::uint32_t value) {
  std::uint32_t node = 1;
  for (int i = Bits - 1; i >= 0; --i) node = 2 * node + static_cast<std::uint32_t>(io.bit(tree[node], (value >> i) & 1u));
  return node - (1u << Bits);
}

// A face's size: real faces by a tree of 3..9 sides with an escape, holes as integers.
template <typename Channel>
std::int64_t code_size(Channel& io, Models& m, FaceKind owner, bool hole, std::int64_t size) {
  if (hole) return 3 + io.integer(m.hole_size, size - 3);
  const std::uint32_t symbol = code_tree<3>(io, m.size[owner], static_cast<std::uint32_t>(std::min<std::int64_t>(size - 3, 7)));
  return symbol < 7 ? 3 + symbol : 10 + io.integer(m.large_size, size - 10);
}

enum Chain { kBack, kForward, kMiddle };

// A chain length in unary, walking the border from slot s (backward, or
// forward for kForward); each decision's context is the faces already around
// the corner it leaves.
template <typename Channel>
std::uint32_t code_chain(Channel& io, Models& m, const Border& border, Chain chain, std::uint32_t s, bool hole,
                         std::uint32_t limit, std::uint32_t value) {
  std::uint32_t count = 0;
  while (count < limit) {
    const int faces = border.faces_at(border.slot(s).vertex);
    if (!io.bit(m.chain[chain][hole][static_cast<std::size_t>(faces)], count < value)) break;
    s = chain == kForward ? border.slot(s).next : border.slot(s).prev;
    ++count;
  }
  return count;
}

// The slot starting an existing run: near the gate as a direction and a
// distance along the border, else by its age.
template <typename Channel>
const char* code_split_slot(Channel& io, Models& m, const Border& border, std::uint32_t& slot) {
  const std::uint32_t g = border.gate();
  std::uint32_t distance = 0;
  int backward = 0;
  for (std::uint32_t d = 1, ahead = g, behind = g; d <= kNearSlots && slot != kNone && distance == 0; ++d) {
    ahead = border.slot(ahead).next;
    behind = border.slot(behind).prev;
    if (ahead == slot || behind == slot) {
      distance = d;
      backward = ahead != slot;
    }
  }
  if (io.bit(m.near, distance != 0)) {
    backward = io.bit(m.near_backward, backward);
    distance = 1 + code_tree<kNearBits>(io, m.near_distance, distance - 1);
    slot = g;
    for (std::uint32_t d = 0; d < distance; ++d) slot = backward ? border.slot(slot).prev : border.slot(slot).next;
    return nullptr;
  }
  const std::int64_t slots = border.slot_count();
  const std::int64_t age = io.integer(m.slot_age, slot == kNone ? 0 : slots - 1 - slot);
  if (age < 0 || age >= slots || !border.alive(static_cast<std::uint32_t>(slots - 1 - age))) return "a border slot out of range";
  slot = static_cast<std::uint32_t>(slots - 1 - age);
  return nullptr;
}

// The face across the gate. The encoder passes its shape; the decoder an
// empty one and the largest sizes it may still take. Returns nullptr or what
// is impossible.
template <typename Channel>
const char* code_face(Channel& io, Models& m, const Border& border, std::uint64_t max_face, std::uint64_t max_hole,
                      FaceShape& shape) {
  const FaceKind owner = border.slot(border.gate()).owner;
  shape.hole = io.bit(m.hole[owner], shape.hole) != 0;
  const std::int64_t size = code_size(io, m, owner, shape.hole, shape.size);
  if (size < 3 || static_cast<std::uint64_t>(size) > std::min(kMaxFaceSize, shape.hole ? max_hole : max_face))
    return "an impossible face size";
  shape.size = static_cast<std::uint32_t>(size);
  const std::uint32_t g = border.gate();
  shape.back = code_chain(io, m, border, kBack, g, shape.hole, shape.size - 1, shape.back);
  const bool closes = shape.back + 1 == shape.size;
  const std::uint32_t limit = closes ? 0 : shape.size - 2 - shape.back;
  shape.forward = closes ? 0 : code_chain(io, m, border, kForward, border.slot(g).next, shape.hole, limit, shape.forward);
  std::uint32_t remaining = limit - shape.forward;
  for (std::size_t i = 0; remaining > 0; ++i) {
    if (io.exhausted()) return "the coded data ends early";
    MiddleRun run = i < shape.middle.size() ? shape.middle[i] : MiddleRun{};
    if (io.bit(m.existing[shape.hole], run.slot != kNone)) {
      if (const char* problem = code_split_slot(io, m, border, run.slot)) return problem;
      run.chain = code_chain(io, m, border, kMiddle, run.slot, shape.hole, remaining - 1, run.chain);
    } else {
      run = MiddleRun{};
    }
    if (i < shape.middle.size()) shape.middle[i] = run;
    else shape.middle.push_back(run);
    remaining -= 1 + run.chain;
  }
  return nullptr;
}

// Sharp flags in vertex order: one flag for "any", then one per vertex.
template <typename Channel>
void code_sharp(Channel& io, Models& m, std::uint32_t vertices, std::vector<std::uint8_t>& sharp) {
  if (!io.bit(m.any_sharp, !sharp.empty())) return;
  sharp.resize(vertices, 0);
  int previous = 0;
  for (std::uint8_t& flag : sharp) {
    flag = static_cast<std::uint8_t>(io.bit(m.sharp[static_cast<std::size_t>(previous)], flag != 0));
    previous = flag;
  }
  if (std::none_of(sharp.begin(), sharp.end(), [](std::uint8_t f) { return f != 0; })) sharp.clear();
}

// ------------------------------------------------------------ encoder side

// The mesh's faces, then one hole face per boundary loop (its vertices in
// reverse order), with every half-edge's twin: a closed surface.
struct ClosedMesh {
  std::vector<std::uint32_t> offsets;
  std::vector<std::uint32_t> vertices;  // per half-edge (corner): its start vertex
  std::vector<std::uint32_t> face_of;   // per half-edge
  std::vector<std::uint32_t> twin;      // per half-edge
  std::uint32_t real_faces = 0;

  std::uint32_t face_count() const { return static_cast<std::uint32_t>(offsets.size() - 1); }
  std::uint32_t size(std::uint32_t f) const { return offsets[f + 1] - offsets[f]; }
  // Half-edge k (mod size) of face f.
  std::uint32_t corner(std::uint32_t f, std::uint32_t k) const { return offsets[f] + k % size(f); }
  std::uint32_t next(std::uint32_t h) const { return h + 1 == offsets[face_of[h] + 1] ? offsets[face_of[h]] : h + 1; }
  std::uint32_t prev(std::uint32_t h) const { return h == offsets[face_of[h]] ? offsets[face_of[h] + 1] - 1 : h - 1; }
};

void add_face(ClosedMesh& c, const std::vector<std::uint32_t>& face) {
  const auto f = c.face_count();
  c.vertices.insert(c.vertices.end(), face.begin(), face.end());
  c.face_of.insert(c.face_of.end(), face.size(), f);
  c.offsets.push_back(static_cast<std::uint32_t>(c.vertices.size()));
}

// Twins through each vertex's outgoing half-edges (O(corners x valence)).
void match_twins(ClosedMesh& c, std::size_t vertex_count, std::vector<std::uint32_t>& out_start,
                 std::vector<std::uint32_t>& out) {
  const auto corners = static_cast<std::uint32_t>(c.vertices.size());
  out_start.assign(vertex_count + 1, 0);
  for (std::uint32_t h = 0; h < corners; ++h) ++out_start[c.vertices[h] + 1];
  for (std::size_t v = 0; v < vertex_count; ++v) out_start[v + 1] += out_start[v];
  out.resize(corners);
  std::vector<std::uint32_t> fill(out_start.begin(), out_start.end() - 1);
  for (std::uint32_t h = 0; h < corners; ++h) out[fill[c.vertices[h]]++] = h;
  c.twin.assign(corners, kNone);
  for (std::uint32_t h = 0; h < corners; ++h) {
    const std::uint32_t a = c.vertices[h], b = c.vertices[c.next(h)];
    for (std::uint32_t i = out_start[b]; i < out_start[b + 1]; ++i)
      if (c.vertices[c.next(out[i])] == a) c.twin[h] = out[i];
  }
}

ClosedMesh close_holes(const PolygonMesh& mesh) {
  ClosedMesh c;
  c.offsets = mesh.face_offsets;
  c.vertices = mesh.face_vertices;
  c.real_faces = static_cast<std::uint32_t>(mesh.face_count());
  c.face_of.resize(c.vertices.size());
  for (std::uint32_t f = 0; f < c.real_faces; ++f)
    std::fill(c.face_of.begin() + c.offsets[f], c.face_of.begin() + c.offsets[f + 1], f);
  std::vector<std::uint32_t> out_start, out;
  match_twins(c, mesh.vertex_count(), out_start, out);
  const auto real_corners = static_cast<std::uint32_t>(mesh.face_vertices.size());
  const auto boundary_out = [&](std::uint32_t v) {
    for (std::uint32_t i = out_start[v]; i < out_start[v + 1]; ++i)
      if (c.twin[out[i]] == kNone) return out[i];
    return kNone;
  };
  std::vector<std::uint32_t> loop, hole;
  for (std::uint32_t h0 = 0; h0 < real_corners; ++h0) {
    if (c.twin[h0] != kNone) continue;
    loop.clear();  // boundary half-edges v_0 -> v_1 -> ... ; the hole runs backwards
    for (std::uint32_t h = h0; h != kNone && (loop.empty() || h != h0); h = boundary_out(c.vertices[c.next(h)])) {
      loop.push_back(h);
      if (loop.size() > real_corners) break;  // not a manifold (a broken precondition)
    }
    assert(!loop.empty() && loop.size() <= real_corners);
    const auto k = loop.size();
    const auto first = static_cast<std::uint32_t>(c.vertices.size());
    hole.clear();
    for (std::size_t i = 0; i < k; ++i) hole.push_back(c.vertices[loop[(k - i) % k]]);
    add_face(c, hole);
    c.twin.resize(c.vertices.size(), kNone);
    for (std::size_t i = 0; i < k; ++i) {
      const std::uint32_t boundary = loop[(2 * k - i - 1) % k];
      c.twin[first + i] = boundary;
      c.twin[boundary] = first + static_cast<std::uint32_t>(i);
    }
  }
  return c;
}

// The encoder's run of the border machine over a mesh: it reads each face's
// shape from the mesh, codes it through the channel and records the order.
class Traversal {
 public:
  Traversal(const PolygonMesh& mesh, RangeEncoder* rc)
      : closed_(close_holes(mesh)), io_{rc}, processed_(closed_.face_count(), 0),
        half_slot_(closed_.vertices.size(), kNone), new_of_old(mesh.vertex_count(), kNone) {
    ordered.face_vertices.reserve(mesh.face_vertices.size());
    ordered.face_offsets.reserve(mesh.face_offsets.size());
    for (std::uint32_t f = 0; f < closed_.real_faces; ++f)
      if (!processed_[f]) code_component(f);
    io_.bit(models_.component, 0);
  }

  Models& models() { return models_; }
  EncodeChannel& channel() { return io_; }

 private:
  void code_component(std::uint32_t seed_face) {
    io_.bit(models_.component, 1);
    const std::uint32_t n = closed_.size(seed_face);
    code_size(io_, models_, kFaceKinds, false, n);
    border_.seed(n, face_);
    for (std::uint32_t k = 0; k < n; ++k) add_slot(closed_.corner(seed_face, k));
    record(seed_face, 0);
    while (border_.gate() != kNone) code_face_at_gate();
  }

  void code_face_at_gate() {
    const std::uint32_t across = closed_.twin[slot_half_[border_.gate()]];  // w -> u
    const std::uint32_t f = closed_.face_of[across];
    const std::uint32_t start = across - closed_.offsets[f];
    read_shape(f, start);
    // Neither fails on a manifold mesh; a broken precondition stops here
    // instead of looping.
    const char* problem = code_face(io_, models_, border_, kNone, kNone, shape_);
    if (!problem) problem = border_.attach(shape_, face_);
    if (problem) throw Error(ErrorKind::Topology, std::string("base mesh connectivity: not a manifold mesh: ") + problem);
    // The new slots are the face's unconsumed edges after x_back, in order.
    for (std::uint32_t k = shape_.back + 1; border_.slot_count() > slot_half_.size(); ++k) {
      const std::uint32_t h = closed_.corner(f, start + k);
      if (!processed_[closed_.face_of[closed_.twin[h]]]) add_slot(h);
    }
    record(f, start);
  }

  // Corner k of face f in gate order is closed_.corner(f, start + k): w, u, x_1, ...
  void read_shape(std::uint32_t f, std::uint32_t start) {
    const std::uint32_t n = closed_.size(f);
    const auto processed_across = [&](std::uint32_t k) {
      return processed_[closed_.face_of[closed_.twin[closed_.corner(f, start + k)]]] != 0;
    };
    shape_.size = n;
    shape_.hole = f >= closed_.real_faces;
    shape_.back = 0;
    while (shape_.back < n - 1 && processed_across(1 + shape_.back)) ++shape_.back;
    shape_.forward = 0;
    if (shape_.back < n - 1)
      while (shape_.forward < n - 2 - shape_.back && processed_across(n - 1 - shape_.forward)) ++shape_.forward;
    shape_.middle.clear();
    for (std::uint32_t k = shape_.back + 2; k + shape_.forward < n;) {
      const std::uint32_t h = closed_.corner(f, start + k);
      MiddleRun run;
      if (new_of_old[closed_.vertices[h]] != kNone) {
        run.slot = wedge_slot(closed_.prev(h));
        while (k + run.chain + 1 + shape_.forward < n && processed_across(k + run.chain)) ++run.chain;
      }
      shape_.middle.push_back(run);
      k += 1 + run.chain;
    }
  }

  // The border slot bounding the wedge of unprocessed faces that holds the
  // half-edge `in` (which ends at an existing vertex z): rotate around z
  // through unprocessed faces to the first processed half-edge out of z.
  std::uint32_t wedge_slot(std::uint32_t in) const {
    for (std::size_t steps = 0; steps <= closed_.vertices.size(); ++steps) {
      const std::uint32_t out = closed_.twin[in];
      if (processed_[closed_.face_of[out]]) return half_slot_[out];
      in = closed_.prev(out);
    }
    assert(false && "a vertex whose faces form no fan");
    return kNone;
  }

  void add_slot(std::uint32_t half_edge) {
    half_slot_[half_edge] = static_cast<std::uint32_t>(slot_half_.size());
    slot_half_.push_back(half_edge);
  }

  // Numbers the face's new vertices and appends it when it is a mesh face.
  void record(std::uint32_t f, std::uint32_t start) {
    processed_[f] = 1;
    const std::uint32_t n = closed_.size(f);
    for (std::uint32_t k = 0; k < n; ++k) {
      std::uint32_t& number = new_of_old[closed_.vertices[closed_.corner(f, start + k)]];
      assert(number == kNone || number == face_[k]);
      number = face_[k];
    }
    if (f < closed_.real_faces) ordered.add_face(face_.data(), face_.size());
  }

  ClosedMesh closed_;
  Border border_;
  Models models_;
  EncodeChannel io_;
  std::vector<std::uint8_t> processed_;    // per face of closed_
  std::vector<std::uint32_t> slot_half_;   // per slot: its half-edge in closed_
  std::vector<std::uint32_t> half_slot_;   // per half-edge: its slot, if it became one
  FaceShape shape_;
  std::vector<std::uint32_t> face_;

 public:
  std::vector<std::uint32_t> new_of_old;
  PolygonMesh ordered;  // the faces in traversal order and numbering; no positions
};

bool is_identity(const std::vector<std::uint32_t>& map) {
  for (std::size_t i = 0; i < map.size(); ++i)
    if (map[i] != i) return false;
  return true;
}

bool sharp_is_normal(const PolygonMesh& mesh) { return mesh.sharp.empty() || mesh.sharp_count() > 0; }

// ------------------------------------------------------------ decoder side

class Decoder {
 public:
  Decoder(RangeDecoder& rc, const ConnectivityCounts& expected) : io_{rc}, expected_(expected) {}

  PolygonMesh run() {
    while (io_.bit(models_.component, 0)) {
      decode_seed();
      while (border_.gate() != kNone) decode_face();
    }
    code_sharp(io_, models_, border_.vertex_count(), mesh_.sharp);
    if (io_.exhausted()) fail("the coded data ends early");
    if (border_.vertex_count() != expected_.vertices || mesh_.face_count() != expected_.faces ||
        mesh_.face_vertices.size() != expected_.corners)
      fail("the decoded counts differ from the stored ones");
    mesh_.positions.assign(border_.vertex_count(), Vec3{});
    try {
      require_manifold(mesh_, "the decoded base mesh");
    } catch (const Error& error) {
      fail(error.what());
    }
    return std::move(mesh_);
  }

 private:
  [[noreturn]] static void fail(const std::string& what) {
    throw Error(ErrorKind::Format, "base mesh connectivity: " + what);
  }

  void decode_seed() {
    if (io_.exhausted()) fail("the coded data ends early");
    const std::int64_t n = code_size(io_, models_, kFaceKinds, false, 0);
    if (n < 3 || static_cast<std::uint64_t>(n) > std::min(kMaxFaceSize, remaining_corners())) fail("an impossible face size");
    border_.seed(static_cast<std::uint32_t>(n), face_);
    append_face();
  }

  void decode_face() {
    if (io_.exhausted()) fail("the coded data ends early");
    shape_.middle.clear();  // the decoder's shape starts empty (code_face fills it)
    const std::uint64_t max_hole = expected_.corners - std::min(expected_.corners, hole_corners_);
    if (const char* problem = code_face(io_, models_, border_, remaining_corners(), max_hole, shape_)) fail(problem);
    if (const char* problem = border_.attach(shape_, face_)) fail(problem);
    if (shape_.hole) hole_corners_ += shape_.size;
    else append_face();
    if (border_.vertex_count() > expected_.vertices) fail("more vertices than stored");
  }

  void append_face() {
    if (mesh_.face_count() >= expected_.faces) fail("more faces than stored");
    mesh_.add_face(face_.data(), face_.size());
  }

  std::uint64_t remaining_corners() const {
    return expected_.corners - std::min<std::uint64_t>(expected_.corners, mesh_.face_vertices.size());
  }

  DecodeChannel io_;
  ConnectivityCounts expected_;
  Models models_;
  Border border_;
  FaceShape shape_;
  std::vector<std::uint32_t> face_;
  PolygonMesh mesh_;
  std::uint64_t hole_corners_ = 0;
};

}  // namespace

CanonicalMesh canonical_order(const PolygonMesh& mesh) {
  Traversal t(mesh, nullptr);
  CanonicalMesh result;
  result.mesh = std::move(t.ordered);
  result.mesh.positions.resize(mesh.vertex_count());
  for (std::size_t v = 0; v < mesh.vertex_count(); ++v) result.mesh.positions[t.new_of_old[v]] = mesh.positions[v];
  if (mesh.sharp_count() > 0) {
    result.mesh.sharp.assign(mesh.vertex_count(), 0);
    for (std::size_t v = 0; v < mesh.vertex_count(); ++v) result.mesh.sharp[t.new_of_old[v]] = mesh.sharp[v];
  }
  result.new_of_old = std::move(t.new_of_old);
  return result;
}

bool is_canonical(const PolygonMesh& mesh) {
  const Traversal t(mesh, nullptr);
  return is_identity(t.new_of_old) && t.ordered.face_offsets == mesh.face_offsets &&
         t.ordered.face_vertices == mesh.face_vertices && sharp_is_normal(mesh);
}

ConnectivityCounts connectivity_counts(const PolygonMesh& mesh) {
  return {mesh.vertex_count(), mesh.face_count(), mesh.face_vertices.size()};
}

void encode_connectivity(RangeEncoder& rc, const PolygonMesh& canonical) {
  Traversal t(canonical, &rc);
  if (!is_identity(t.new_of_old) || t.ordered.face_offsets != canonical.face_offsets ||
      t.ordered.face_vertices != canonical.face_vertices || !sharp_is_normal(canonical))
    throw Error(ErrorKind::InvalidArgument, "encode_connectivity: the base mesh is not in canonical order");
  std::vector<std::uint8_t> sharp = canonical.sharp;
  code_sharp(t.channel(), t.models(), static_cast<std::uint32_t>(canonical.vertex_count()), sharp);
}

PolygonMesh decode_connectivity(RangeDecoder& rc, const ConnectivityCounts& expected) {
  return Decoder(rc, expected).run();
}

}  // namespace isowave::detail
