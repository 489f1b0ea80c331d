
#include "Logger.hpp"
#include "SlaveInstance.hpp"
#include "fmi/fmi2Functions.h"
#include "fmu_except.hpp"

#include <charconv>
#include <cmath>
#include <exception>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <regex>
#include <set>
#include <stdexcept>
#include <string>

namespace
{

class Fmi2Logger : public pythonfmu::PyLogger
{

public:
    explicit Fmi2Logger(const std::string& instanceName, const fmi2CallbackFunctions* f)
        : PyLogger(instanceName)
        , f_(f)
    { }

protected:
    void debugLog(fmi2Status s, const std::string& category, const std::string& message) override
    {
        // prandtl_fmu: never a NULL category (PyLogger names one); no logger, no call
        if (f_ != nullptr && f_->logger != nullptr) {
            f_->logger(f_->componentEnvironment, instanceName_.c_str(), s, category.c_str(), message.c_str());
        }
    }

private:
    const fmi2CallbackFunctions* f_;
};

// A struct that holds all the data for one model instance.
struct Fmi2Component
{

    Fmi2Component(std::unique_ptr<pythonfmu::SlaveInstance> slave, std::unique_ptr<Fmi2Logger> logger)
        : slave(std::move(slave))
        , logger(std::move(logger))
    { }

    // prandtl_fmu: the start time until a step is taken (the stock loader answered NaN)
    double lastSuccessfulTime{0.0};
    bool wantsToTerminate{false};
    // prandtl_fmu: where the instance is in FMI 2.0's co-simulation call sequence (4.2.4). A step refused with
    // fmi2Discard leaves it stepping: the instance is unchanged and a master may set a good input and step again.
    // A refused call (fmi2Error) leaves it where it was: every refusal changes nothing.
    enum Mode : unsigned { instantiated = 1, initialization = 2, stepping = 4, terminated = 8 };
    Mode mode{instantiated};

    std::unique_ptr<pythonfmu::SlaveInstance> slave;
    std::unique_ptr<Fmi2Logger> logger;
};

// prandtl_fmu: the calls each mode allows, as the Reference-FMUs' masks for co-simulation (getters also after
// fmi2Terminate: the master reads the final values then; setters not after it; the status inquiries once
// stepping; fmi2DoStep never returns fmi2Pending, so fmi2CancelStep is never allowed)
constexpr unsigned ANY_MODE = Fmi2Component::instantiated | Fmi2Component::initialization | Fmi2Component::stepping
    | Fmi2Component::terminated;
constexpr unsigned GETTERS = Fmi2Component::initialization | Fmi2Component::stepping | Fmi2Component::terminated;
constexpr unsigned SETTERS = Fmi2Component::instantiated | Fmi2Component::initialization | Fmi2Component::stepping;
constexpr unsigned STATUS = Fmi2Component::stepping | Fmi2Component::terminated;

const char* modeName(unsigned mode)
{
    switch (mode) {
        case Fmi2Component::instantiated: return "before fmi2EnterInitializationMode";
        case Fmi2Component::initialization: return "in initialization mode";
        case Fmi2Component::stepping: return "after initialization";
        default: return "after fmi2Terminate";
    }
}

// prandtl_fmu: the instances fmi2Instantiate returned and fmi2FreeInstance has not freed, and the FMU states
// fmi2GetFMUstate and fmi2DeSerializeFMUstate returned and fmi2FreeFMUstate has not freed (with how many
// slots hold each). A NULL or unknown instance is refused with fmi2Error (nobody to log to: the stock loader
// dereferenced it), a NULL or unknown state with the reason: a freed or made-up pointer is never touched.
// States are the library's, not an instance's: one may be set into another instance of the same FMU (the slave
// checks that it fits).
std::mutex registryMutex;
std::set<const void*> liveInstances;
std::map<const void*, unsigned> liveStates;

Fmi2Component* live(fmi2Component c)
{
    const auto lock = std::lock_guard{registryMutex};
    return c != nullptr && liveInstances.count(c) != 0 ? static_cast<Fmi2Component*>(c) : nullptr;
}

bool isState(fmi2FMUstate state)
{
    const auto lock = std::lock_guard{registryMutex};
    return state != nullptr && liveStates.count(state) != 0;
}

void remember(fmi2FMUstate state)
{
    const auto lock = std::lock_guard{registryMutex};
    ++liveStates[state];
}

void forget(fmi2FMUstate state)
{
    const auto lock = std::lock_guard{registryMutex};
    const auto found = liveStates.find(state);
    if (found != liveStates.end() && --found->second == 0) {
        liveStates.erase(found);
    }
}

// prandtl_fmu: a call refused for its arguments (logged as fmi2Error with this text; the instance unchanged)
struct refused : std::runtime_error
{
    explicit refused(const std::string& what)
        : std::runtime_error(what + "; the instance is unchanged")
    { }
};

// the shortest text that reads back as `value`, whatever the host's locale (as Python's repr: 0.1, 1e+51, nan)
std::string number(double value)
{
    char text[32];
    const auto end = std::to_chars(text, text + sizeof text, value).ptr;
    return std::string(text, end);
}

void requireNotNull(const void* pointer, const char* function, const char* argument)
{
    if (pointer == nullptr) {
        throw refused(std::string(function) + " refused: " + argument + " is NULL");
    }
}

// an array argument of nvr elements: NULL only with nvr = 0
void requireArray(const void* pointer, size_t nvr, const char* function, const char* argument)
{
    if (pointer == nullptr && nvr > 0) {
        throw refused(std::string(function) + " refused: " + argument + " is NULL with nvr = " + std::to_string(nvr));
    }
}

// prandtl_fmu: every FMI function but fmi2Instantiate and fmi2FreeInstance runs here: a NULL or unknown instance
// is fmi2Error, a call the mode does not allow is refused with the reason logged (fmi2Error, always logged), and
// no exception crosses into the host (the stock loader let anything but std::exception terminate it).
template <typename Body>
fmi2Status guarded(fmi2Component c, unsigned modes, const char* function, Body&& body)
{
    Fmi2Component* component = live(c);
    if (component == nullptr) {
        return fmi2Error;
    }
    if ((component->mode & modes) == 0) {
        component->logger->log(fmi2Error, std::string(function) + " refused: not allowed " + modeName(component->mode)
            + " (FMI 2.0 co-simulation call sequence); the instance is unchanged");
        return fmi2Error;
    }
    try {
        return body(*component);
    } catch (const pythonfmu::fatal_error& e) {
        component->logger->log(fmi2Fatal, e.what());
        return fmi2Fatal;
    } catch (const std::exception& e) {
        component->logger->log(fmi2Error, e.what());
        return fmi2Error;
    } catch (...) {
        component->logger->log(fmi2Error, std::string(function) + " failed with an unknown exception");
        return fmi2Error;
    }
}

fmi2Status unsupported(fmi2Component c, unsigned modes, const char* function)
{
    return guarded(c, modes, function, [function](Fmi2Component& component) {
        component.logger->log(fmi2Error, std::string("FMI function not supported: ") + function);
        return fmi2Error;
    });
}

// fmi2Get*Status for a kind it does not answer: fmi2Discard with the reason, as the Reference-FMUs do; a NULL
// value or a kind that is no fmi2StatusKind is fmi2Error
fmi2Status statusNotAvailable(Fmi2Component& component, fmi2StatusKind s, const void* value, const char* function)
{
    requireNotNull(value, function, "value");
    if (s < fmi2DoStepStatus || s > fmi2Terminated) {
        throw refused(std::string(function) + " refused: " + std::to_string(static_cast<int>(s))
            + " is not an fmi2StatusKind");
    }
    component.logger->log(fmi2Discard, std::string(function) + ": status kind " + std::to_string(static_cast<int>(s))
        + " is not available (fmi2DoStep never returns fmi2Pending; fmi2GetRealStatus answers "
          "fmi2LastSuccessfulTime and fmi2GetBooleanStatus fmi2Terminated)");
    return fmi2Discard;
}

} // namespace


// FMI functions
extern "C" {

// =============================================================================
// FMI 2.0 functions
// =============================================================================


const char* fmi2GetTypesPlatform()
{
    return fmi2TypesPlatform;
}


const char* fmi2GetVersion()
{
    return "2.0";
}


fmi2Component fmi2Instantiate(fmi2String instanceName,
    fmi2Type fmuType,
    fmi2String fmuGUID,
    fmi2String fmuResourceLocation,
    const fmi2CallbackFunctions* functions,
    fmi2Boolean visible,
    fmi2Boolean loggingOn)
{

    // prandtl_fmu: a missing argument is logged and refused (std::string of NULL is undefined behaviour)
    if (functions == nullptr || functions->logger == nullptr) {
        return nullptr;
    }
    if (instanceName == nullptr || fmuResourceLocation == nullptr) {
        functions->logger(functions->componentEnvironment, instanceName != nullptr ? instanceName : "", fmi2Error,
            "logStatusError", "fmi2Instantiate refused: instanceName and fmuResourceLocation must not be NULL");
        return nullptr;
    }
    // prandtl_fmu: the FMU is co-simulation only (its modelDescription declares no ModelExchange)
    if (fmuType != fmi2CoSimulation) {
        functions->logger(functions->componentEnvironment, instanceName, fmi2Error, "logStatusError",
            "fmi2Instantiate refused: this FMU implements co-simulation only (fmuType must be fmi2CoSimulation)");
        return nullptr;
    }

    try {
        // Convert URI %20 to space
        auto resources = std::regex_replace(std::string(fmuResourceLocation), std::regex("%20"), " ");
        const auto find = resources.find("file://");

        if (find != std::string::npos) {
#ifdef _MSC_VER
            resources.replace(find, 8, "");
#else
            resources.replace(find, 7, "");
#endif
        }

        auto logger = std::make_unique<Fmi2Logger>(instanceName, functions);
        logger->setDebugLogging(loggingOn);
        try {
            auto instance = pythonfmu::createInstance(
                {logger.get(),
                    visible == fmi2True,
                    instanceName,
                    resources,
                    nullptr});

            auto component = std::make_unique<Fmi2Component>(std::move(instance), std::move(logger));
            const auto lock = std::lock_guard{registryMutex};
            liveInstances.insert(component.get());
            return component.release();
        } catch (const std::exception& e) {
            logger->log(fmi2Fatal, e.what());
            return nullptr;
        }
    } catch (...) {
        return nullptr;
    }
}


void fmi2FreeInstance(fmi2Component c)
{
    // prandtl_fmu: a NULL, unknown or already freed instance is left alone (the stock loader freed it again)
    {
        const auto lock = std::lock_guard{registryMutex};
        if (c == nullptr || liveInstances.erase(c) == 0) {
            return;
        }
    }
    delete static_cast<Fmi2Component*>(c);
}


fmi2Status fmi2SetDebugLogging(
    fmi2Component c,
    fmi2Boolean loggingOn,
    size_t nCategories,
    const fmi2String categories[])
{
    return guarded(c, ANY_MODE, "fmi2SetDebugLogging", [&](Fmi2Component& component) {
        requireArray(categories, nCategories, "fmi2SetDebugLogging", "categories");
        std::vector<std::string> categoriesVec;
        categoriesVec.reserve(nCategories);
        for (size_t i = 0; i < nCategories; ++i) {
            if (categories[i] == nullptr) {
                throw refused("fmi2SetDebugLogging refused: categories[" + std::to_string(i) + "] is NULL");
            }
            categoriesVec.emplace_back(categories[i]);
        }
        component.logger->setDebugLogging(loggingOn, categoriesVec);
        return fmi2OK;
    });
}


fmi2Status fmi2SetupExperiment(
    fmi2Component c,
    fmi2Boolean toleranceDefined,
    fmi2Real tolerance,
    fmi2Real startTime,
    fmi2Boolean stopTimeDefined,
    fmi2Real stopTime)
{
    return guarded(c, Fmi2Component::instantiated, "fmi2SetupExperiment", [&](Fmi2Component& component) {
        // prandtl_fmu: the clock starts at a finite time (the stock loader took NaN and inf: the clock became NaN)
        if (!std::isfinite(startTime)) {
            throw refused("fmi2SetupExperiment refused: startTime = " + number(startTime) + " must be finite");
        }
        if (stopTimeDefined && !(std::isfinite(stopTime) && stopTime >= startTime)) {
            throw refused("fmi2SetupExperiment refused: stopTime = " + number(stopTime)
                + " must be finite and >= startTime = " + number(startTime));
        }
        if (toleranceDefined && !(std::isfinite(tolerance) && tolerance >= 0)) {
            throw refused("fmi2SetupExperiment refused: tolerance = " + number(tolerance) + " must be finite and >= 0");
        }
        component.slave->SetupExperiment(
            startTime,
            stopTimeDefined ? std::optional(stopTime) : std::nullopt,
            toleranceDefined ? std::optional(tolerance) : std::nullopt);
        component.lastSuccessfulTime = startTime;
        return fmi2OK;
    });
}


fmi2Status fmi2EnterInitializationMode(fmi2Component c)
{
    return guarded(c, Fmi2Component::instantiated, "fmi2EnterInitializationMode", [](Fmi2Component& component) {
        component.slave->EnterInitializationMode();
        component.mode = Fmi2Component::initialization;
        return fmi2OK;
    });
}


fmi2Status fmi2ExitInitializationMode(fmi2Component c)
{
    return guarded(c, Fmi2Component::initialization, "fmi2ExitInitializationMode", [](Fmi2Component& component) {
        component.slave->ExitInitializationMode();
        component.mode = Fmi2Component::stepping;
        return fmi2OK;
    });
}


fmi2Status fmi2Terminate(fmi2Component c)
{
    return guarded(c, Fmi2Component::stepping, "fmi2Terminate", [](Fmi2Component& component) {
        component.slave->Terminate();
        component.mode = Fmi2Component::terminated;
        return fmi2OK;
    });
}


fmi2Status fmi2Reset(fmi2Component c)
{
    return guarded(c, ANY_MODE, "fmi2Reset", [](Fmi2Component& component) {
        component.slave->Reset();
        component.mode = Fmi2Component::instantiated;
        component.lastSuccessfulTime = 0.0;
        component.wantsToTerminate = false;
        return fmi2OK;
    });
}


fmi2Status fmi2GetReal(
    fmi2Component c,
    const fmi2ValueReference vr[],
    size_t nvr,
    fmi2Real value[])
{
    return guarded(c, GETTERS, "fmi2GetReal", [&](Fmi2Component& component) {
        requireArray(vr, nvr, "fmi2GetReal", "vr");
        requireArray(value, nvr, "fmi2GetReal", "value");
        component.slave->GetReal(vr, nvr, value);
        return fmi2OK;
    });
}

fmi2Status fmi2GetInteger(
    fmi2Component c,
    const fmi2ValueReference vr[],
    size_t nvr,
    fmi2Integer value[])
{
    return guarded(c, GETTERS, "fmi2GetInteger", [&](Fmi2Component& component) {
        requireArray(vr, nvr, "fmi2GetInteger", "vr");
        requireArray(value, nvr, "fmi2GetInteger", "value");
        component.slave->GetInteger(vr, nvr, value);
        return fmi2OK;
    });
}

fmi2Status fmi2GetBoolean(
    fmi2Component c,
    const fmi2ValueReference vr[],
    size_t nvr,
    fmi2Boolean value[])
{
    return guarded(c, GETTERS, "fmi2GetBoolean", [&](Fmi2Component& component) {
        requireArray(vr, nvr, "fmi2GetBoolean", "vr");
        requireArray(value, nvr, "fmi2GetBoolean", "value");
        component.slave->GetBoolean(vr, nvr, value);
        return fmi2OK;
    });
}

fmi2Status fmi2GetString(
    fmi2Component c,
    const fmi2ValueReference vr[],
    size_t nvr,
    fmi2String value[])
{
    return guarded(c, GETTERS, "fmi2GetString", [&](Fmi2Component& component) {
        requireArray(vr, nvr, "fmi2GetString", "vr");
        requireArray(value, nvr, "fmi2GetString", "value");
        component.slave->GetString(vr, nvr, value);
        return fmi2OK;
    });
}


fmi2Status fmi2SetReal(
    fmi2Component c,
    const fmi2ValueReference vr[],
    size_t nvr,
    const fmi2Real value[])
{
    return guarded(c, SETTERS, "fmi2SetReal", [&](Fmi2Component& component) {
        requireArray(vr, nvr, "fmi2SetReal", "vr");
        requireArray(value, nvr, "fmi2SetReal", "value");
        component.slave->SetReal(vr, nvr, value);
        return fmi2OK;
    });
}

fmi2Status fmi2SetInteger(
    fmi2Component c,
    const fmi2ValueReference vr[],
    size_t nvr,
    const fmi2Integer value[])
{
    return guarded(c, SETTERS, "fmi2SetInteger", [&](Fmi2Component& component) {
        requireArray(vr, nvr, "fmi2SetInteger", "vr");
        requireArray(value, nvr, "fmi2SetInteger", "value");
        component.slave->SetInteger(vr, nvr, value);
        return fmi2OK;
    });
}

fmi2Status fmi2SetBoolean(
    fmi2Component c,
    const fmi2ValueReference vr[],
    size_t nvr,
    const fmi2Boolean value[])
{
    return guarded(c, SETTERS, "fmi2SetBoolean", [&](Fmi2Component& component) {
        requireArray(vr, nvr, "fmi2SetBoolean", "vr");
        requireArray(value, nvr, "fmi2SetBoolean", "value");
        component.slave->SetBoolean(vr, nvr, value);
        return fmi2OK;
    });
}

fmi2Status fmi2SetString(
    fmi2Component c,
    const fmi2ValueReference vr[],
    size_t nvr,
    const fmi2String value[])
{
    return guarded(c, SETTERS, "fmi2SetString", [&](Fmi2Component& component) {
        requireArray(vr, nvr, "fmi2SetString", "vr");
        requireArray(value, nvr, "fmi2SetString", "value");
        // prandtl_fmu: a NULL string is no string (the stock loader handed the slave None)
        for (size_t i = 0; i < nvr; ++i) {
            if (value[i] == nullptr) {
                throw refused("fmi2SetString refused: value[" + std::to_string(i) + "] (value reference "
                    + std::to_string(vr[i]) + ") is NULL, not a string");
            }
        }
        component.slave->SetString(vr, nvr, value);
        return fmi2OK;
    });
}


// prandtl_fmu: the FMU-state functions refuse NULL and unknown states (the stock loader dereferenced a NULL
// pointer and released whatever it was given) and keep the registry of live states.
fmi2Status fmi2GetFMUstate(
    fmi2Component c,
    fmi2FMUstate* state)
{
    return guarded(c, ANY_MODE, "fmi2GetFMUstate", [&](Fmi2Component& component) {
        requireNotNull(state, "fmi2GetFMUstate", "FMUstate (where the state is returned)");
        const fmi2FMUstate previous = *state;
        if (previous != nullptr && !isState(previous)) {
            throw refused("fmi2GetFMUstate refused: *FMUstate is neither NULL nor a state of this FMU");
        }
        component.slave->GetFMUstate(*state); // releases the previous state (FMI 2.0: overwritten)
        if (previous != nullptr) {
            forget(previous);
        }
        remember(*state);
        return fmi2OK;
    });
}

fmi2Status fmi2SetFMUstate(
    fmi2Component c,
    fmi2FMUstate state)
{
    return guarded(c, ANY_MODE, "fmi2SetFMUstate", [&](Fmi2Component& component) {
        requireNotNull(state, "fmi2SetFMUstate", "FMUstate");
        if (!isState(state)) {
            throw refused("fmi2SetFMUstate refused: FMUstate is not a state of this FMU (or was freed)");
        }
        component.slave->SetFMUstate(state);
        return fmi2OK;
    });
}

fmi2Status fmi2FreeFMUstate(
    fmi2Component c,
    fmi2FMUstate* state)
{
    return guarded(c, ANY_MODE, "fmi2FreeFMUstate", [&](Fmi2Component& component) {
        if (state == nullptr || *state == nullptr) {
            return fmi2OK; // FMI 2.0 (2.1.8): a null pointer is ignored
        }
        if (!isState(*state)) {
            throw refused("fmi2FreeFMUstate refused: *FMUstate is not a state of this FMU (or was freed)");
        }
        const fmi2FMUstate freed = *state;
        component.slave->FreeFMUstate(*state);
        forget(freed);
        return fmi2OK;
    });
}

fmi2Status fmi2SerializedFMUstateSize(
    fmi2Component c,
    fmi2FMUstate state,
    size_t* size)
{
    return guarded(c, ANY_MODE, "fmi2SerializedFMUstateSize", [&](Fmi2Component& component) {
        requireNotNull(size, "fmi2SerializedFMUstateSize", "size");
        requireNotNull(state, "fmi2SerializedFMUstateSize", "FMUstate");
        if (!isState(state)) {
            throw refused("fmi2SerializedFMUstateSize refused: FMUstate is not a state of this FMU (or was freed)");
        }
        *size = component.slave->SerializedFMUstateSize(state);
        return fmi2OK;
    });
}

fmi2Status fmi2SerializeFMUstate(
    fmi2Component c,
    fmi2FMUstate state,
    fmi2Byte bytes[],
    size_t size)
{
    return guarded(c, ANY_MODE, "fmi2SerializeFMUstate", [&](Fmi2Component& component) {
        requireNotNull(state, "fmi2SerializeFMUstate", "FMUstate");
        requireNotNull(bytes, "fmi2SerializeFMUstate", "serializedState");
        if (!isState(state)) {
            throw refused("fmi2SerializeFMUstate refused: FMUstate is not a state of this FMU (or was freed)");
        }
        component.slave->SerializeFMUstate(state, bytes, size);
        return fmi2OK;
    });
}

fmi2Status fmi2DeSerializeFMUstate(
    fmi2Component c,
    const fmi2Byte bytes[],
    size_t size,
    fmi2FMUstate* state)
{
    return guarded(c, ANY_MODE, "fmi2DeSerializeFMUstate", [&](Fmi2Component& component) {
        requireNotNull(state, "fmi2DeSerializeFMUstate", "FMUstate (where the state is returned)");
        requireArray(bytes, size, "fmi2DeSerializeFMUstate", "serializedState");
        const fmi2FMUstate previous = *state;
        if (previous != nullptr && !isState(previous)) {
            throw refused("fmi2DeSerializeFMUstate refused: *FMUstate is neither NULL nor a state of this FMU");
        }
        component.slave->DeSerializeFMUstate(bytes, size, *state); // releases the previous state
        if (previous != nullptr) {
            forget(previous);
        }
        remember(*state);
        return fmi2OK;
    });
}


fmi2Status fmi2GetDirectionalDerivative(
    fmi2Component c,
    const fmi2ValueReference[],
    size_t,
    const fmi2ValueReference[],
    size_t,
    const fmi2Real[],
    fmi2Real[])
{
    return unsupported(c, GETTERS, "fmi2GetDirectionalDerivative");
}

fmi2Status fmi2SetRealInputDerivatives(
    fmi2Component c,
    const fmi2ValueReference[],
    size_t,
    const fmi2Integer[],
    const fmi2Real[])
{
    return unsupported(c, SETTERS, "fmi2SetRealInputDerivatives");
}

fmi2Status fmi2GetRealOutputDerivatives(
    fmi2Component c,
    const fmi2ValueReference[],
    size_t,
    const fmi2Integer[],
    fmi2Real[])
{
    return unsupported(c, STATUS, "fmi2GetRealOutputDerivatives");
}

fmi2Status fmi2DoStep(
    fmi2Component c,
    fmi2Real currentCommunicationPoint,
    fmi2Real communicationStepSize,
    fmi2Boolean /*noSetFMUStatePriorToCurrentPoint*/)
{
    return guarded(c, Fmi2Component::stepping, "fmi2DoStep", [&](Fmi2Component& component) {
        // prandtl_fmu: a finite clock and a finite step >= 0 whose end is finite (the stock loader took NaN, inf
        // and negative steps with fmi2OK: the clock became NaN)
        if (!std::isfinite(currentCommunicationPoint)) {
            throw refused("fmi2DoStep refused: currentCommunicationPoint = " + number(currentCommunicationPoint)
                + " must be finite");
        }
        if (!(std::isfinite(communicationStepSize) && communicationStepSize >= 0)) {
            throw refused("fmi2DoStep refused: communicationStepSize = " + number(communicationStepSize)
                + " must be finite and >= 0");
        }
        if (!std::isfinite(currentCommunicationPoint + communicationStepSize)) {
            throw refused("fmi2DoStep refused: the step from " + number(currentCommunicationPoint) + " by "
                + number(communicationStepSize) + " ends at a time that is not finite");
        }
        if (component.slave->DoStep(currentCommunicationPoint, communicationStepSize)) {
            component.lastSuccessfulTime = currentCommunicationPoint + communicationStepSize;
            // prandtl_fmu: fmi2Terminated tells about the last step (the stock loader kept it true for ever
            // after the first Discard, although a master may fix an input and step on)
            component.wantsToTerminate = false;
            return fmi2OK;
        }
        component.lastSuccessfulTime = currentCommunicationPoint;
        component.wantsToTerminate = true;
        return fmi2Discard;
    });
}

fmi2Status fmi2CancelStep(fmi2Component c)
{
    // prandtl_fmu: fmi2DoStep never returns fmi2Pending: there is never a step to cancel (the Reference-FMUs' mask)
    return guarded(c, ANY_MODE, "fmi2CancelStep", [](Fmi2Component& component) {
        component.logger->log(fmi2Error, "fmi2CancelStep refused: fmi2DoStep never returns fmi2Pending, so there is "
            "no step in progress to cancel");
        return fmi2Error;
    });
}


/* Inquire slave status */
fmi2Status fmi2GetStatus(
    fmi2Component c,
    const fmi2StatusKind s,
    fmi2Status* value)
{
    return guarded(c, STATUS, "fmi2GetStatus", [&](Fmi2Component& component) {
        return statusNotAvailable(component, s, value, "fmi2GetStatus");
    });
}

fmi2Status fmi2GetRealStatus(
    fmi2Component c,
    const fmi2StatusKind s,
    fmi2Real* value)
{
    return guarded(c, STATUS, "fmi2GetRealStatus", [&](Fmi2Component& component) {
        requireNotNull(value, "fmi2GetRealStatus", "value");
        if (s == fmi2LastSuccessfulTime) {
            *value = component.lastSuccessfulTime;
            return fmi2OK;
        }
        return statusNotAvailable(component, s, value, "fmi2GetRealStatus");
    });
}

fmi2Status fmi2GetIntegerStatus(
    fmi2Component c,
    const fmi2StatusKind s,
    fmi2Integer* value)
{
    return guarded(c, STATUS, "fmi2GetIntegerStatus", [&](Fmi2Component& component) {
        return statusNotAvailable(component, s, value, "fmi2GetIntegerStatus");
    });
}

fmi2Status fmi2GetBooleanStatus(
    fmi2Component c,
    const fmi2StatusKind s,
    fmi2Boolean* value)
{
    return guarded(c, STATUS, "fmi2GetBooleanStatus", [&](Fmi2Component& component) {
        requireNotNull(value, "fmi2GetBooleanStatus", "value");
        if (s == fmi2Terminated) {
            *value = component.wantsToTerminate ? fmi2True : fmi2False;
            return fmi2OK;
        }
        return statusNotAvailable(component, s, value, "fmi2GetBooleanStatus");
    });
}

fmi2Status fmi2GetStringStatus(
    fmi2Component c,
    const fmi2StatusKind s,
    fmi2String* value)
{
    return guarded(c, STATUS, "fmi2GetStringStatus", [&](Fmi2Component& component) {
        return statusNotAvailable(component, s, value, "fmi2GetStringStatus");
    });
}
}
