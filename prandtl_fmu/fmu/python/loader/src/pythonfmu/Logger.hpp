
#ifndef PYTHONFMU_LOGGER_HPP
#define PYTHONFMU_LOGGER_HPP

#include "fmi/fmi2Functions.h"

#include <algorithm>
#include <string>
#include <vector>

namespace pythonfmu
{

class PyLogger
{

public:
    explicit PyLogger(std::string instanceName)
        : instanceName_(std::move(instanceName))
    { }

    void setDebugLogging(bool flag, const std::vector<std::string>& categories = {})
    {
        debugLogging_ = flag;
        categories_ = categories;
    }

    // Logs a message.
    void log(fmi2Status s, const std::string& message)
    {
        log(s, "", message);
    }

    // prandtl_fmu: a warning, a Discard, an error or a fatal error always reaches the host's logger, whatever
    // loggingOn and fmi2SetDebugLogging say (as the Reference-FMUs do: with logging off a refusal was silent);
    // those filter the other messages only. A message without a category gets the one of its status, which the
    // modelDescription declares (the stock loader passed NULL, and OMSimulator aborts on a NULL category).
    void log(fmi2Status s, const std::string& category, const std::string& message)
    {
        const std::string named = category.empty() ? statusCategory(s) : category;
        if (s != fmi2OK && s != fmi2Pending) {
            debugLog(s, named, message);
        } else if (debugLogging_) {
            if (categories_.empty() || std::find(categories_.begin(), categories_.end(), named) != categories_.end()) {
                debugLog(s, named, message);
            }
        }
    }

    // prandtl_fmu: the categories PythonFMU's Fmi2Slave declares (log_categories) and derives from a status
    static const char* statusCategory(fmi2Status s)
    {
        switch (s) {
            case fmi2Warning: return "logStatusWarning";
            case fmi2Discard: return "logStatusDiscard";
            case fmi2Error: return "logStatusError";
            case fmi2Fatal: return "logStatusFatal";
            default: return "logAll";
        }
    }

    virtual ~PyLogger() = default;

private:
    bool debugLogging_{false};

protected:
    std::string instanceName_;
    std::vector<std::string> categories_;

    virtual void debugLog(fmi2Status s, const std::string& category, const std::string& message) = 0;
};

} // namespace pythonfmu

#endif // PYTHONFMU_LOGGER_HPP
