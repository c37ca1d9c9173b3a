// dpts-mpi's messages (see mpi_pieces.hpp).
#include "apps/mpi_pieces.hpp"

#include <mpi.h>

#include <cstdint>
#include <cstring>
#include <limits>
#include <stdexcept>

namespace dpts::mpi {
namespace {

// Message tags: a piece (its index, then its bytes), a failure (its message), the end.
constexpr int kPiece = 1, kError = 2, kEnd = 3;
bool g_went = false;

void check(int code, const char* what) {
  if (code != MPI_SUCCESS) throw std::runtime_error(std::string("MPI: ") + what + " failed");
}

void send(const std::string& bytes, int tag) {
  if (bytes.size() > static_cast<std::size_t>(std::numeric_limits<int>::max())) {
    throw std::runtime_error(
        "MPI: a piece of more than 2 GB cannot be sent; use a smaller --tile-mb");
  }
  check(MPI_Send(bytes.data(), static_cast<int>(bytes.size()), MPI_CHAR, 0, tag, MPI_COMM_WORLD),
        "send");
}

}  // namespace

void init(int& argc, char**& argv) {
  int provided = 0;
  check(MPI_Init_thread(&argc, &argv, MPI_THREAD_FUNNELED, &provided), "init");
}

void finalize() { MPI_Finalize(); }

int rank() {
  int r = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &r);
  return r;
}

int ranks() {
  int n = 1;
  MPI_Comm_size(MPI_COMM_WORLD, &n);
  return n;
}

bool go(bool ok) {
  int word = ok ? 1 : 0;
  check(MPI_Bcast(&word, 1, MPI_INT, 0, MPI_COMM_WORLD), "broadcast");
  g_went = true;
  return word == 1;
}

bool went() { return g_went; }

std::vector<std::size_t> share(std::size_t pieces, int r, int n) {
  std::vector<std::size_t> out;
  for (std::size_t i = static_cast<std::size_t>(r); i < pieces; i += static_cast<std::size_t>(n)) {
    out.push_back(i);
  }
  return out;
}

void send_piece(std::size_t index, const std::string& bytes) {
  std::string message(sizeof(std::uint64_t), '\0');
  const std::uint64_t i = index;
  std::memcpy(message.data(), &i, sizeof(i));
  message += bytes;
  send(message, kPiece);
}

void send_error(const std::string& message) { send(message, kError); }

void send_end() { send(std::string(), kEnd); }

std::string receive(std::vector<par::QemPieceMesh>& outputs, par::MetaStats& st,
                    const std::function<void()>& received) {
  std::string failure;
  for (int open = ranks() - 1; open > 0;) {
    MPI_Status status;
    check(MPI_Probe(MPI_ANY_SOURCE, MPI_ANY_TAG, MPI_COMM_WORLD, &status), "probe");
    int count = 0;
    MPI_Get_count(&status, MPI_CHAR, &count);
    std::string bytes(static_cast<std::size_t>(count), '\0');
    check(MPI_Recv(bytes.data(), count, MPI_CHAR, status.MPI_SOURCE, status.MPI_TAG, MPI_COMM_WORLD,
                   MPI_STATUS_IGNORE),
          "receive");
    const std::string from = "rank " + std::to_string(status.MPI_SOURCE) + ": ";
    if (status.MPI_TAG == kEnd) {
      --open;
    } else if (status.MPI_TAG == kError) {
      --open;
      if (failure.empty()) failure = from + bytes;
    } else {
      std::uint64_t index = 0;
      if (bytes.size() >= sizeof(index)) std::memcpy(&index, bytes.data(), sizeof(index));
      if (bytes.size() < sizeof(index) || index >= outputs.size()) {
        if (failure.empty()) failure = from + "a message that is not a piece";
        continue;
      }
      try {
        par::from_bytes(bytes.substr(sizeof(index)), outputs[index], st.pieces[index]);
      } catch (const std::exception& e) {
        if (failure.empty()) failure = from + e.what();
      }
      if (received) received();
    }
  }
  return failure;
}

}  // namespace dpts::mpi
