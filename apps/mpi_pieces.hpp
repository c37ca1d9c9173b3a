// dpts-mpi's messages: rank 0 plans and merges, every rank simplifies a share of the qem
// engine's pieces (TBB inside each) and sends them to rank 0. Only the main thread of each
// rank calls MPI (MPI_THREAD_FUNNELED).
#pragma once

#include <cstddef>
#include <functional>
#include <string>
#include <vector>

#include "parallel/qem_engine.hpp"

namespace dpts::mpi {

// Starts and ends MPI (once per process).
void init(int& argc, char**& argv);
void finalize();
int rank();
int ranks();

// Rank 0's word to the other ranks, once it has planned (true) or failed before (false): every
// rank calls it exactly once; returns rank 0's word.
bool go(bool ok);
// Whether this rank has called go.
bool went();

// The pieces rank r simplifies: i % ranks == r, so that the ranks share neighbouring (similar)
// pieces evenly.
std::vector<std::size_t> share(std::size_t pieces, int r, int ranks);

// A rank other than 0: its pieces, one message each, then the end (or why it failed).
void send_piece(std::size_t index, const std::string& bytes);
void send_error(const std::string& message);
void send_end();

// Rank 0: every other rank's pieces into outputs and st.pieces, until each has ended or
// failed; calls received() after each piece. Returns the first failure's message (naming its
// rank), empty when none.
std::string receive(std::vector<par::QemPieceMesh>& outputs, par::MetaStats& st,
                    const std::function<void()>& received);

}  // namespace dpts::mpi
