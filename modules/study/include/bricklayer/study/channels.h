// Channels of a study session (see lcmtypes/study_*_t.lcm). Use bricklayer::channel() to apply the
// deployment's prefix.
#pragma once

#include "bricklayer/common/channels.h"

namespace bricklayer::study {

// The session, problem and command channels are declared with the bus's other channels (common/channels.h), since
// projection (a stage that may not include this module's headers) reads and writes them.
inline constexpr const char* kSessionChannel = bricklayer::kStudySessionChannel;  // study_session_t, on change and 1 Hz
inline constexpr const char* kTrialChannel = "BL_STUDY_TRIAL";      // study_trial_t, session driver, once per game
inline constexpr const char* kProblemChannel = bricklayer::kStudyProblemChannel;  // study_problem_t, session driver, per problem step
inline constexpr const char* kAnswerChannel = "BL_STUDY_ANSWER";    // study_answer_t, session driver, once per answer
using bricklayer::kStudyCommandChannel;  // study_command_t, experimenter (or projection's key D) -> session driver

}  // namespace bricklayer::study
