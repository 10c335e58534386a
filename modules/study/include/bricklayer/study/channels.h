// Channels of a study session (see lcmtypes/study_*_t.lcm). Use bricklayer::channel() to apply the
// deployment's prefix.
#pragma once

namespace bricklayer::study {

inline constexpr const char* kSessionChannel = "BL_STUDY_SESSION";  // study_session_t, session driver, on change and 1 Hz
inline constexpr const char* kTrialChannel = "BL_STUDY_TRIAL";      // study_trial_t, session driver, once per game
inline constexpr const char* kProblemChannel = "BL_STUDY_PROBLEM";  // study_problem_t, session driver, per problem step
inline constexpr const char* kAnswerChannel = "BL_STUDY_ANSWER";    // study_answer_t, session driver, once per answer
inline constexpr const char* kStudyCommandChannel = "BL_STUDY_COMMAND";  // study_command_t, experimenter -> session driver

}  // namespace bricklayer::study
