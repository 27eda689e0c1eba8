// vpm as a DICOM node (vpm-server --dicom-listen AET@HOST:PORT): a C-STORE
// and C-ECHO receiver on a thread of its own. Each association runs on a
// thread of its own (StoreAssociation), at most `max_associations` at once
// (more are rejected, "local limit exceeded"); associations that call
// another AE title are rejected. Stop() (and the destructor) closes the
// port, cuts the associations still running, and joins every thread:
// their partial series are dropped.
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <list>
#include <memory>
#include <mutex>
#include <set>
#include <string>
#include <thread>

#include "server/common/status.h"
#include "server/pacs/dimse_address.h"
#include "server/pacs/move_registry.h"
#include "server/pacs/received_store.h"
#include "server/pacs/store_association.h"

struct T_ASC_Network;
struct T_ASC_Association;

namespace vpm::pacs {

class DicomListener {
 public:
  struct Options {
    DimseAddress address;  // AE title, host, port (0: any free port)
    int max_associations = 8;
    int64_t max_instance_bytes = int64_t{1} << 30;  // bytes of one instance
    int64_t acse_timeout_s = 10;                    // association negotiation
    int64_t dimse_timeout_s = 60;                   // between two messages of the sender
    ReceivedStore* store = nullptr;                 // required; outlives the listener
    MoveRegistry* moves = nullptr;                  // optional; outlives the listener
    std::set<std::string> own_move_originators;     // StoreAssociation::Context
    std::function<void(const ReceiveReport&)> on_series;  // each series of an association
  };
  // Opens the port. InvalidArgument naming --dicom-listen when it cannot.
  static Result<std::unique_ptr<DicomListener>> Start(Options options);
  ~DicomListener();

  // Idempotent; returns once every association thread has ended (within
  // about a second: running associations are cut, not waited for).
  void Stop();
  int port() const { return port_; }

 private:
  struct Worker {
    std::thread thread;
    int socket = -1;
    bool done = false;
  };
  explicit DicomListener(Options options);
  void AcceptLoop();
  void RunAssociation(T_ASC_Association* association);
  void ReapFinished();

  Options options_;
  T_ASC_Network* network_ = nullptr;
  int port_ = 0;
  std::atomic<bool> stopping_{false};
  std::mutex mutex_;  // workers_
  std::list<Worker> workers_;
  std::thread acceptor_;
  struct Config;
  std::unique_ptr<Config> config_;
};

}  // namespace vpm::pacs
