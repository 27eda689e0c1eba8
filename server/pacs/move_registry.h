// The C-MOVEs under way, so that the DICOM listener hands their instances
// to the retrieval that asked for them instead of to the received store.
// A move is expected for one series from one PACS (its AE title, the
// calling AE of the association that brings the instances) and, when the
// C-STORE says so, for vpm's own AE title as the move originator. Its
// instances go into the retrieval's private folder (the series cache's
// temporary folder), under its byte budget.
#pragma once

#include <condition_variable>
#include <cstdint>
#include <filesystem>
#include <map>
#include <memory>
#include <mutex>
#include <string>

#include "server/common/cancel_token.h"
#include "server/common/status.h"

namespace vpm::pacs {

class MoveRegistry {
 public:
  // Where one move's instances go.
  class Sink {
   public:
    // Moves the received file `file` (`bytes` long) into the move's folder
    // under a name of vpm's; ResourceExhausted past the budget (the move
    // then fails), Internal when it cannot be moved.
    Status Keep(const std::filesystem::path& file, int64_t bytes);
    void Fail(const Status& status);

   private:
    friend class MoveRegistry;
    std::filesystem::path folder_;
    int64_t max_bytes_ = 0;
    std::mutex mutex_;
    std::condition_variable changed_;
    int64_t instances_ = 0, bytes_ = 0;
    Status failure_;
  };

  // A move's registration, removed with the object.
  class Expectation {
   public:
    ~Expectation();
    // Waits until `instances` have arrived (the PACS's count of completed
    // sub-operations), the move failed, `cancel` fires, or `timeout_s`
    // passes (DeadlineExceeded: the PACS said they were sent, vpm did not
    // get them all).
    Status WaitFor(int64_t instances, const CancelToken& cancel, double timeout_s) const;
    int64_t instances() const;
    int64_t bytes() const;
    Status failure() const;

   private:
    friend class MoveRegistry;
    MoveRegistry* registry_ = nullptr;
    std::string key_;
    std::shared_ptr<Sink> sink_;
  };

  // Expects the instances of `series_uid` sent by `peer_ae` for a move
  // that `originator_ae` asked for. FailedPrecondition when that move is
  // under way already.
  Result<std::unique_ptr<Expectation>> Expect(const std::string& series_uid,
                                              const std::string& peer_ae,
                                              const std::string& originator_ae,
                                              const std::filesystem::path& folder,
                                              int64_t max_bytes);

  // The sink of the move an instance of `series_uid`, sent by `calling_ae`
  // with MoveOriginatorApplicationEntityTitle `originator_ae` (empty when
  // the C-STORE carries none), belongs to; null when none.
  std::shared_ptr<Sink> Route(const std::string& series_uid, const std::string& calling_ae,
                              const std::string& originator_ae) const;

 private:
  struct Entry {
    std::string originator_ae;
    std::shared_ptr<Sink> sink;
  };
  mutable std::mutex mutex_;
  std::map<std::string, Entry> moves_;  // by "SERIES_UID PEER_AE"
};

}  // namespace vpm::pacs
