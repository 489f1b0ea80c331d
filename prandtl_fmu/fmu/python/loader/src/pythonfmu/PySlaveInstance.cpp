
#include "fmu_except.hpp"

#include "pythonfmu/Logger.hpp"
#include "pythonfmu/PyState.hpp"
#include "pythonfmu/SlaveInstance.hpp"

#include <filesystem>
#include <fstream>
#include <cstring>
#include <functional>
#include <mutex>
#include <regex>
#include <sstream>
#include <string>
#include <utility>

using namespace pythonfmu;

// prandtl_fmu: the name the slave receives as its ``pythonfmu_loader`` argument (fmu/common.py): the stock
// loader passes none, and the slave then compensates that loader's reference counting.
static const char* const PRANDTL_LOADER_NAME = "prandtl_fmu";

namespace
{
std::string getline(const std::filesystem::path& fileName)
{
    std::string line;
    std::ifstream infile(fileName);
    std::getline(infile, line);
    return line;
}

// prandtl_fmu: the stock findClass released a reference to the module's dict that it never took (the host
// crashed after enough instantiations), leaked the repr and UTF-8 copy of every class name it read, called
// Py_Finalize (the host's interpreter!) on a syntax error and ignored an exception raised by the script. This
// one releases exactly what it owns, returns nullptr with the Python exception set on any failure (the caller
// reports it), and marks the module's globals with ``__prandtl_loader__`` so that the script knows that no
// reference is taken from them (fmu/entry.py compensates the stock loader only).
PyObject* findClass(const std::string& resources, const std::string& moduleName)
{
    const std::string filename = resources + "/" + moduleName + ".py";
    std::ifstream file(filename);
    if (!file.is_open()) {
        PyErr_SetString(PyExc_FileNotFoundError, ("cannot read the slave script " + filename).c_str());
        return nullptr;
    }
    std::stringstream contents;
    contents << file.rdbuf();

    PyObject* pyModule = PyImport_ImportModule(moduleName.c_str());
    if (pyModule == nullptr) {
        return nullptr;
    }
    PyObject* pGlobals = PyModule_GetDict(pyModule); // borrowed
    if (PyDict_SetItemString(pGlobals, "__prandtl_loader__", Py_True) != 0) {
        Py_DECREF(pyModule);
        return nullptr;
    }
    // Executed again, as the stock loader does: the classes it binds are the ones looked for.
    PyObject* pLocals = PyDict_New();
    PyObject* pCode = Py_CompileString(contents.str().c_str(), filename.c_str(), Py_file_input);
    PyObject* pResult = pCode != nullptr ? PyEval_EvalCode(pCode, pGlobals, pLocals) : nullptr;
    Py_XDECREF(pCode);
    Py_DECREF(pyModule);
    if (pResult == nullptr) {
        Py_DECREF(pLocals);
        return nullptr;
    }
    Py_DECREF(pResult);

    // The class bound by the script whose MRO reaches Fmi2Slave deepest.
    PyObject* pyClass = nullptr;
    Py_ssize_t deepestChain = 0;
    PyObject *key, *value;
    Py_ssize_t pos = 0;
    while (PyDict_Next(pLocals, &pos, &key, &value)) {
        if (!PyType_Check(value)) {
            continue;
        }
        PyObject* pMro = PyObject_GetAttrString(value, "__mro__");
        if (pMro == nullptr) {
            PyErr_Clear();
            continue;
        }
        const Py_ssize_t length = PySequence_Check(pMro) ? PySequence_Size(pMro) : 0;
        for (Py_ssize_t i = 0; i < length; ++i) {
            PyObject* pItem = PySequence_GetItem(pMro, i);
            PyObject* pName = pItem != nullptr ? PyObject_GetAttrString(pItem, "__name__") : nullptr;
            const bool isSlave = pName != nullptr && PyUnicode_CompareWithASCIIString(pName, "Fmi2Slave") == 0;
            Py_XDECREF(pName);
            Py_XDECREF(pItem);
            PyErr_Clear();
            if (isSlave && i > deepestChain) {
                pyClass = value;
                deepestChain = i;
            }
        }
        Py_DECREF(pMro);
    }
    Py_XINCREF(pyClass);
    Py_DECREF(pLocals);
    if (pyClass == nullptr) {
        PyErr_SetString(PyExc_RuntimeError, (filename + " binds no subclass of pythonfmu's Fmi2Slave").c_str());
    }
    return pyClass;
}

// prandtl_fmu: the GIL is released on every path, an exception's included (the stock handle_py_exception
// released it itself, and any other exception left it held).
void py_safe_run(const std::function<void(PyGILState_STATE gilState)>& f)
{
    PyGILState_STATE gil_state = PyGILState_Ensure();
    try {
        f(gil_state);
    } catch (...) {
        PyGILState_Release(gil_state);
        throw;
    }
    PyGILState_Release(gil_state);
}

} // namespace

class PySlaveInstance : public SlaveInstance
{
public:
    explicit PySlaveInstance(fmu_data data)
        : data_(std::move(data))
    {
        py_safe_run([this](PyGILState_STATE gilState) {
            // Append resources path to python sys path
            PyObject* sys_module = PyImport_ImportModule("sys");
            if (sys_module == nullptr) {
                handle_py_exception("[ctor] PyImport_ImportModule", gilState);
            }
            PyObject* sys_path = PyObject_GetAttrString(sys_module, "path");
            Py_DECREF(sys_module);
            if (sys_path == nullptr) {
                handle_py_exception("[ctor] PyObject_GetAttrString", gilState);
            }
            PyObject* resources = PyUnicode_FromString(resourceLocation().c_str());
            int success = resources != nullptr ? PyList_Insert(sys_path, 0, resources) : -1;
            Py_XDECREF(resources); // prandtl_fmu: PyList_Insert takes its own reference

            Py_DECREF(sys_path);
            if (success != 0) {
                handle_py_exception("[ctor] PyList_Insert", gilState);
            }

            std::string moduleName = getline(resourceLocation() + "/slavemodule.txt");

            pClass_ = findClass(resourceLocation(), moduleName);
            if (pClass_ == nullptr) {
                handle_py_exception("[ctor] findClass", gilState);
            }

            initialize(gilState);
        });
    }

    void clearLogBuffer() const
    {
        clearLogStrBuffer();

        PyObject* msgField = Py_BuildValue("s", "msg");
        PyObject* categoryField = Py_BuildValue("s", "category");
        PyObject* statusField = Py_BuildValue("s", "status");

        if (pMessages_ != nullptr && PyList_Check(pMessages_)) {
            const auto size = PyList_Size(pMessages_);
            for (auto i = 0; i < size; i++) {
                PyObject* msg = PyList_GetItem(pMessages_, i);

                // prandtl_fmu: the attributes read are released (the stock loader kept three references per
                // message), and a message that cannot be read is skipped, never dereferenced.
                PyObject* msgAttr = PyObject_GetAttr(msg, msgField);
                PyObject* categoryAttr = PyObject_GetAttr(msg, categoryField);
                PyObject* statusAttr = PyObject_GetAttr(msg, statusField);
                PyObject* msgValue = msgAttr != nullptr ? PyUnicode_AsEncodedString(msgAttr, "utf-8", "replace") : nullptr;
                PyObject* categoryValue = categoryAttr != nullptr && categoryAttr != Py_None
                    ? PyUnicode_AsEncodedString(categoryAttr, "utf-8", "replace")
                    : nullptr;
                const auto statusValue = statusAttr != nullptr
                    ? static_cast<fmi2Status>(PyLong_AsLong(statusAttr))
                    : fmi2Error;
                if (msgValue != nullptr) {
                    log(statusValue, categoryValue != nullptr ? PyBytes_AsString(categoryValue) : "",
                        PyBytes_AsString(msgValue));
                }
                Py_XDECREF(msgValue);
                Py_XDECREF(categoryValue);
                Py_XDECREF(msgAttr);
                Py_XDECREF(categoryAttr);
                Py_XDECREF(statusAttr);
                PyErr_Clear();
            }
            PyList_SetSlice(pMessages_, 0, size, nullptr);
        }

        Py_DECREF(msgField);
        Py_DECREF(categoryField);
        Py_DECREF(statusField);
    }

    void initialize(PyGILState_STATE gilState)
    {
        // prandtl_fmu: the released references are forgotten (the stock loader released them again in its
        // destructor when the new instance could not be made), and the slave is told which loader runs it
        // (``pythonfmu_loader``: it then takes no references to compensate for the stock loader's defects).
        Py_CLEAR(pInstance_);
        Py_CLEAR(pMessages_);

        PyObject* args = PyTuple_New(0);
        PyObject* kwargs = Py_BuildValue("{ss,ss,sn,si,ss}",
            "instance_name", data_.instanceName.c_str(),
            "resources", data_.resourceLocation.c_str(),
            "logger", data_.fmiLogger,
            "visible", data_.visible,
            "pythonfmu_loader", PRANDTL_LOADER_NAME);
        pInstance_ = PyObject_Call(pClass_, args, kwargs);
        Py_DECREF(args);
        Py_DECREF(kwargs);
        if (pInstance_ == nullptr) {
            handle_py_exception("[initialize] PyObject_Call", gilState);
        }
        pMessages_ = PyObject_CallMethod(pInstance_, "_get_log_queue", nullptr);
        if (pMessages_ == nullptr) {
            handle_py_exception("[initialize] _get_log_queue", gilState);
        }
    }

    void SetupExperiment(double startTime, std::optional<double> stop, std::optional<double> tolerance) override
    {
        py_safe_run([this, startTime, stop, tolerance](PyGILState_STATE gilState) {
            PyObject* pyStop = stop ? Py_BuildValue("d", *stop) : (Py_INCREF(Py_None), Py_None);
            PyObject* pyTol = tolerance ? Py_BuildValue("d", *tolerance) : (Py_INCREF(Py_None), Py_None);

            auto f = PyObject_CallMethod(pInstance_, "setup_experiment", "(dOO)", startTime, pyStop, pyTol);

            Py_DECREF(pyStop);
            Py_DECREF(pyTol);

            if (f == nullptr) {
                handle_py_exception("[setupExperiment] PyObject_CallMethod", gilState);
            }
            Py_DECREF(f);
            clearLogBuffer();
        });
    }

    void EnterInitializationMode() override
    {
        py_safe_run([this](PyGILState_STATE gilState) {
            auto f = PyObject_CallMethod(pInstance_, "enter_initialization_mode", nullptr);
            if (f == nullptr) {
                handle_py_exception("[enterInitializationMode] PyObject_CallMethod", gilState);
            }
            Py_DECREF(f);
            clearLogBuffer();
        });
    }

    void ExitInitializationMode() override
    {
        py_safe_run([this](PyGILState_STATE gilState) {
            auto f = PyObject_CallMethod(pInstance_, "exit_initialization_mode", nullptr);
            if (f == nullptr) {
                handle_py_exception("[exitInitializationMode] PyObject_CallMethod", gilState);
            }
            Py_DECREF(f);
            clearLogBuffer();
        });
    }

    bool Step(double currentTime, double stepSize) override
    {
        bool status;
        py_safe_run([this, &status, currentTime, stepSize](PyGILState_STATE gilState) {
            auto f = PyObject_CallMethod(pInstance_, "do_step", "(dd)", currentTime, stepSize);
            if (f == nullptr) {
                handle_py_exception("[doStep] PyObject_CallMethod", gilState);
            }
            const int accepted = PyObject_IsTrue(f);
            Py_DECREF(f);
            if (accepted < 0) { // prandtl_fmu: the stock loader took an exception for "accepted"
                handle_py_exception("[doStep] PyObject_IsTrue", gilState);
            }
            status = accepted != 0;
            clearLogBuffer();
        });

        return status;
    }

    void Reset() override
    {
        py_safe_run([this](PyGILState_STATE gilState) {
            initialize(gilState);
        });
    }

    void Terminate() override
    {
        py_safe_run([this](PyGILState_STATE gilState) {
            auto f = PyObject_CallMethod(pInstance_, "terminate", nullptr);
            if (f == nullptr) {
                handle_py_exception("[terminate] PyObject_CallMethod", gilState);
            }
            Py_DECREF(f);
            clearLogBuffer();
        });
    }

    void SetReal(const fmi2ValueReference* vr, std::size_t nvr, const fmi2Real* values) override
    {
        py_safe_run([this, &vr, nvr, &values](PyGILState_STATE gilState) {
            PyObject* vrs = PyList_New(nvr);
            PyObject* refs = PyList_New(nvr);
            for (std::size_t i = 0; i < nvr; i++) {
                PyList_SetItem(vrs, i, PyLong_FromUnsignedLong(vr[i]));
                PyList_SetItem(refs, i, Py_BuildValue("d", values[i]));
            }

            auto f = PyObject_CallMethod(pInstance_, "set_real", "(OO)", vrs, refs);
            Py_DECREF(vrs);
            Py_DECREF(refs);
            if (f == nullptr) {
                handle_py_exception("[setReal] PyObject_CallMethod", gilState);
            }
            Py_DECREF(f);
            clearLogBuffer();
        });
    }

    void SetInteger(const fmi2ValueReference* vr, std::size_t nvr, const fmi2Integer* values) override
    {
        py_safe_run([this, &vr, nvr, &values](PyGILState_STATE gilState) {
            PyObject* vrs = PyList_New(nvr);
            PyObject* refs = PyList_New(nvr);
            for (std::size_t i = 0; i < nvr; i++) {
                PyList_SetItem(vrs, i, PyLong_FromUnsignedLong(vr[i]));
                PyList_SetItem(refs, i, Py_BuildValue("i", values[i]));
            }

            auto f = PyObject_CallMethod(pInstance_, "set_integer", "(OO)", vrs, refs);
            Py_DECREF(vrs);
            Py_DECREF(refs);
            if (f == nullptr) {
                handle_py_exception("[setInteger] PyObject_CallMethod", gilState);
            }
            Py_DECREF(f);
            clearLogBuffer();
        });
    }

    void SetBoolean(const fmi2ValueReference* vr, std::size_t nvr, const fmi2Boolean* values) override
    {
        py_safe_run([this, &vr, nvr, &values](PyGILState_STATE gilState) {
            PyObject* vrs = PyList_New(nvr);
            PyObject* refs = PyList_New(nvr);
            for (std::size_t i = 0; i < nvr; i++) {
                PyList_SetItem(vrs, i, PyLong_FromUnsignedLong(vr[i]));
                PyList_SetItem(refs, i, PyBool_FromLong(values[i]));
            }

            auto f = PyObject_CallMethod(pInstance_, "set_boolean", "(OO)", vrs, refs);
            Py_DECREF(vrs);
            Py_DECREF(refs);
            if (f == nullptr) {
                handle_py_exception("[setBoolean] PyObject_CallMethod", gilState);
            }
            Py_DECREF(f);
            clearLogBuffer();
        });
    }

    void SetString(const fmi2ValueReference* vr, std::size_t nvr, fmi2String const* values) override
    {
        py_safe_run([this, &vr, nvr, &values](PyGILState_STATE gilState) {
            PyObject* vrs = PyList_New(nvr);
            PyObject* refs = PyList_New(nvr);
            for (std::size_t i = 0; i < nvr; i++) {
                PyList_SetItem(vrs, i, PyLong_FromUnsignedLong(vr[i]));
                // prandtl_fmu: a string that is not UTF-8 fails the call (the stock loader put NULL in the list)
                PyObject* text = PyUnicode_DecodeUTF8(values[i], static_cast<Py_ssize_t>(std::strlen(values[i])), "strict");
                if (text == nullptr) {
                    Py_DECREF(vrs);
                    Py_DECREF(refs);
                    handle_py_exception("[setString] value " + std::to_string(i) + " is not UTF-8", gilState);
                }
                PyList_SetItem(refs, i, text);
            }

            auto f = PyObject_CallMethod(pInstance_, "set_string", "(OO)", vrs, refs);
            Py_DECREF(vrs);
            Py_DECREF(refs);
            if (f == nullptr) {
                handle_py_exception("[setString] PyObject_CallMethod", gilState);
            }
            Py_DECREF(f);
            clearLogBuffer();
        });
    }

    void GetReal(const fmi2ValueReference* vr, std::size_t nvr, fmi2Real* values) const override
    {
        py_safe_run([this, &vr, nvr, &values](PyGILState_STATE gilState) {
            PyObject* vrs = PyList_New(nvr);
            for (std::size_t i = 0; i < nvr; i++) {
                PyList_SetItem(vrs, i, PyLong_FromUnsignedLong(vr[i]));
            }

            auto refs = PyObject_CallMethod(pInstance_, "get_real", "O", vrs);
            Py_DECREF(vrs);
            if (refs == nullptr) {
                handle_py_exception("[getReal] PyObject_CallMethod", gilState);
            }
            checkValues(refs, nvr, "[getReal]", gilState);

            for (std::size_t i = 0; i < nvr; i++) {
                PyObject* value = PyList_GetItem(refs, i);
                values[i] = PyFloat_AsDouble(value);
            }
            checkConverted(refs, "[getReal]", gilState);
            Py_DECREF(refs);
            clearLogBuffer();
        });
    }

    void GetInteger(const fmi2ValueReference* vr, std::size_t nvr, fmi2Integer* values) const override
    {
        py_safe_run([this, &vr, nvr, &values](PyGILState_STATE gilState) {
            PyObject* vrs = PyList_New(nvr);
            for (std::size_t i = 0; i < nvr; i++) {
                PyList_SetItem(vrs, i, PyLong_FromUnsignedLong(vr[i]));
            }
            auto refs = PyObject_CallMethod(pInstance_, "get_integer", "O", vrs);
            Py_DECREF(vrs);
            if (refs == nullptr) {
                handle_py_exception("[getInteger] PyObject_CallMethod", gilState);
            }
            checkValues(refs, nvr, "[getInteger]", gilState);

            for (std::size_t i = 0; i < nvr; i++) {
                PyObject* value = PyList_GetItem(refs, i);
                values[i] = static_cast<fmi2Integer>(PyLong_AsLong(value));
            }
            checkConverted(refs, "[getInteger]", gilState);
            Py_DECREF(refs);
            clearLogBuffer();
        });
    }

    void GetBoolean(const fmi2ValueReference* vr, std::size_t nvr, fmi2Boolean* values) const override
    {
        py_safe_run([this, &vr, nvr, &values](PyGILState_STATE gilState) {
            PyObject* vrs = PyList_New(nvr);
            for (std::size_t i = 0; i < nvr; i++) {
                PyList_SetItem(vrs, i, PyLong_FromUnsignedLong(vr[i]));
            }
            auto refs = PyObject_CallMethod(pInstance_, "get_boolean", "O", vrs);
            Py_DECREF(vrs);
            if (refs == nullptr) {
                handle_py_exception("[getBoolean] PyObject_CallMethod", gilState);
            }
            checkValues(refs, nvr, "[getBoolean]", gilState);

            for (std::size_t i = 0; i < nvr; i++) {
                PyObject* value = PyList_GetItem(refs, i);
                values[i] = PyObject_IsTrue(value);
            }
            checkConverted(refs, "[getBoolean]", gilState);
            Py_DECREF(refs);
            clearLogBuffer();
        });
    }

    void GetString(const fmi2ValueReference* vr, std::size_t nvr, fmi2String* values) const override
    {
        py_safe_run([this, &vr, nvr, &values](PyGILState_STATE gilState) {
            clearStrBuffer();
            PyObject* vrs = PyList_New(nvr);
            for (std::size_t i = 0; i < nvr; i++) {
                PyList_SetItem(vrs, i, PyLong_FromUnsignedLong(vr[i]));
            }
            auto refs = PyObject_CallMethod(pInstance_, "get_string", "O", vrs);
            Py_DECREF(vrs);
            if (refs == nullptr) {
                handle_py_exception("[getString] PyObject_CallMethod", gilState);
            }
            checkValues(refs, nvr, "[getString]", gilState);

            for (std::size_t i = 0; i < nvr; i++) {
                PyObject* value = PyUnicode_AsEncodedString(PyList_GetItem(refs, i), "utf-8", nullptr);
                if (value == nullptr) {
                    checkConverted(refs, "[getString]", gilState);
                }
                values[i] = PyBytes_AsString(value);
                strBuffer.emplace_back(value);
            }
            Py_DECREF(refs);
            clearLogBuffer();
        });
    }

    void GetFMUstate(fmi2FMUstate& state) override
    {
        py_safe_run([this, &state](PyGILState_STATE gilState) {
            auto f = PyObject_CallMethod(pInstance_, "_get_fmu_state", nullptr);
            if (f == nullptr) {
                handle_py_exception("[_get_fmu_state] PyObject_CallMethod", gilState);
            }
            // prandtl_fmu: a state passed in (FMI 2.0: one returned earlier, to be overwritten) is released;
            // the stock loader leaked it.
            Py_XDECREF(reinterpret_cast<PyObject*>(state));
            state = reinterpret_cast<fmi2FMUstate*>(f);
            clearLogBuffer();
        });
    }

    void SetFMUstate(const fmi2FMUstate& state) override
    {
        py_safe_run([this, &state](PyGILState_STATE gilState) {
            auto pyState = reinterpret_cast<PyObject*>(state);
            auto f = PyObject_CallMethod(pInstance_, "_set_fmu_state", "(O)", pyState);
            if (f == nullptr) {
                handle_py_exception("[_set_fmu_state] PyObject_CallMethod", gilState);
            }
            Py_DECREF(f); // prandtl_fmu: the stock loader leaked it
            clearLogBuffer();
        });
    }

    void FreeFMUstate(fmi2FMUstate& state) override
    {
        py_safe_run([this, &state](PyGILState_STATE gilState) {
            auto f = reinterpret_cast<PyObject*>(state);
            Py_XDECREF(f);
            state = nullptr; // prandtl_fmu: FMI 2.0 asks for *FMUstate = NULL
        });
    }

    size_t SerializedFMUstateSize(const fmi2FMUstate& state) override
    {
        size_t size;
        py_safe_run([this, &state, &size](PyGILState_STATE gilState) {
            auto pyState = reinterpret_cast<PyObject*>(state);
            PyObject* pyStateBytes = PyObject_CallMethod(pClass_, "_fmu_state_to_bytes", "(O)", pyState);
            if (pyStateBytes == nullptr) {
                handle_py_exception("[SerializedFMUstateSize] PyObject_CallMethod", gilState);
            }
            if (!PyBytes_Check(pyStateBytes)) { // prandtl_fmu: the stock loader answered (size_t)-1
                Py_DECREF(pyStateBytes);
                PyErr_SetString(PyExc_TypeError, "_fmu_state_to_bytes did not return bytes");
                handle_py_exception("[SerializedFMUstateSize] PyBytes_Size", gilState);
            }
            size = static_cast<size_t>(PyBytes_Size(pyStateBytes));
            Py_DECREF(pyStateBytes);
            clearLogBuffer();
        });
        return size;
    }

    void SerializeFMUstate(const fmi2FMUstate& state, fmi2Byte* bytes, size_t size) override
    {
        py_safe_run([this, &state, &bytes, size](PyGILState_STATE gilState) {
            auto pyState = reinterpret_cast<PyObject*>(state);
            PyObject* pyStateBytes = PyObject_CallMethod(pClass_, "_fmu_state_to_bytes", "(O)", pyState);
            if (pyStateBytes == nullptr) {
                handle_py_exception("[SerializeFMUstate] PyObject_CallMethod", gilState);
            }
            char* c = PyBytes_AsString(pyStateBytes);
            if (c == nullptr || static_cast<size_t>(PyBytes_Size(pyStateBytes)) != size) {
                // prandtl_fmu: the stock loader copied `size` bytes whatever the state's length
                if (c != nullptr) {
                    PyErr_SetString(PyExc_ValueError, "the serialized state's size changed since fmi2SerializedFMUstateSize");
                }
                Py_DECREF(pyStateBytes);
                handle_py_exception("[SerializeFMUstate] PyBytes_AsString", gilState);
            }
            for (std::size_t i = 0; i < size; i++) {
                bytes[i] = c[i];
            }
            Py_DECREF(pyStateBytes);
            clearLogBuffer();
        });
    }

    void DeSerializeFMUstate(const fmi2Byte bytes[], size_t size, fmi2FMUstate& state) override
    {
        py_safe_run([this, &bytes, size, &state](PyGILState_STATE gilState) {
            if (size > static_cast<size_t>(PY_SSIZE_T_MAX)) {
                PyErr_SetString(PyExc_OverflowError, "the serialized state's size is larger than any state");
                handle_py_exception("[DeSerializeFMUstate] size", gilState);
            }
            PyObject* pyStateBytes = PyBytes_FromStringAndSize(bytes, static_cast<Py_ssize_t>(size));
            if (pyStateBytes == nullptr) {
                handle_py_exception("[DeSerializeFMUstate] PyBytes_FromStringAndSize", gilState);
            }
            PyObject* pyState = PyObject_CallMethod(pClass_, "_fmu_state_from_bytes", "(O)", pyStateBytes);
            Py_DECREF(pyStateBytes);
            if (pyState == nullptr) {
                handle_py_exception("[DeSerializeFMUstate] PyObject_CallMethod", gilState);
            }
            // prandtl_fmu: a state passed in (one returned earlier) is released, as by GetFMUstate
            Py_XDECREF(reinterpret_cast<PyObject*>(state));
            state = reinterpret_cast<fmi2FMUstate*>(pyState);
            clearLogBuffer();
        });
    }

    ~PySlaveInstance() override
    {
        py_safe_run([this](PyGILState_STATE) {
            cleanPyObject();
        });
    }

private:
    fmu_data data_;

    PyObject* pClass_{};
    PyObject* pInstance_{};
    PyObject* pMessages_{};

    mutable std::vector<PyObject*> strBuffer;
    mutable std::vector<PyObject*> logStrBuffer;

    std::string resourceLocation() const
    {
        return data_.resourceLocation;
    }

    void log(fmi2Status s, const std::string& message) const
    {
        data_.fmiLogger->log(s, message);
    }

    void log(fmi2Status s, const std::string& category, const std::string& message) const
    {
        data_.fmiLogger->log(s, category, message);
    }

    void clearStrBuffer() const
    {
        if (!strBuffer.empty()) {
            for (auto obj : strBuffer) {
                Py_DECREF(obj);
            }
            strBuffer.clear();
        }
    }

    void clearLogStrBuffer() const
    {
        if (!logStrBuffer.empty()) {
            for (auto obj : logStrBuffer) {
                Py_DECREF(obj);
            }
            logStrBuffer.clear();
        }
    }

    void cleanPyObject() const
    {
        clearLogBuffer();
        clearLogStrBuffer();
        clearStrBuffer();
        Py_XDECREF(pClass_);
        Py_XDECREF(pInstance_);
        Py_XDECREF(pMessages_);
    }


    // prandtl_fmu: a failed Python call fails the FMI call with fmi2Error (a std::runtime_error, which fmi2.cpp
    // maps to fmi2Error; the stock loader threw fatal_error: fmi2Fatal) and leaves the instance as it was, so that
    // the host may go on with it (FMI 2.0: after fmi2Error, fmi2SetFMUstate to an earlier state, fmi2Reset or
    // fmi2FreeInstance). The stock loader released pClass_, pInstance_ and pMessages_ here and again in the
    // destructor (a double free: two refused fmi2SetFMUstate calls and a fmi2GetReal crashed the host), and
    // released the GIL itself (py_safe_run does it now). The messages the slave logged before failing are
    // passed on first: they give the reason. Never returns.
    [[noreturn]] void handle_py_exception(const std::string& what, PyGILState_STATE) const
    {
        PyObject *pExcType, *pExcValue, *pExcTraceback;
        PyErr_Fetch(&pExcType, &pExcValue, &pExcTraceback);

        std::ostringstream oss;
        oss << "Python exception in " << what << ": ";
        if (pExcType != nullptr) {
            PyObject* pName = PyObject_GetAttrString(pExcType, "__name__");
            PyObject* pStr = pExcValue != nullptr ? PyObject_Str(pExcValue) : nullptr;
            PyObject* pNameBytes = pName != nullptr ? PyUnicode_AsEncodedString(pName, "utf-8", "replace") : nullptr;
            PyObject* pStrBytes = pStr != nullptr ? PyUnicode_AsEncodedString(pStr, "utf-8", "replace") : nullptr;
            oss << (pNameBytes != nullptr ? PyBytes_AsString(pNameBytes) : "exception");
            if (pStrBytes != nullptr && PyBytes_Size(pStrBytes) > 0) {
                oss << ": " << PyBytes_AsString(pStrBytes);
            }
            Py_XDECREF(pNameBytes);
            Py_XDECREF(pStrBytes);
            Py_XDECREF(pName);
            Py_XDECREF(pStr);
        } else {
            oss << "a Python call failed without an exception";
        }
        Py_XDECREF(pExcType);
        Py_XDECREF(pExcValue);
        Py_XDECREF(pExcTraceback);
        PyErr_Clear();

        clearLogBuffer();
        PyErr_Clear();
        throw std::runtime_error(oss.str());
    }

    // prandtl_fmu: a getter's result is a list of at least nvr values (the stock loader read past a short one).
    void checkValues(PyObject* refs, std::size_t nvr, const std::string& what, PyGILState_STATE gilState) const
    {
        if (!PyList_Check(refs) || PyList_Size(refs) < static_cast<Py_ssize_t>(nvr)) {
            Py_DECREF(refs);
            PyErr_SetString(PyExc_ValueError, "the slave returned fewer values than were asked for");
            handle_py_exception(what, gilState);
        }
    }

    // prandtl_fmu: a value that could not be converted fails the call (the stock loader returned -1 silently).
    void checkConverted(PyObject* refs, const std::string& what, PyGILState_STATE gilState) const
    {
        if (PyErr_Occurred() != nullptr) {
            Py_DECREF(refs);
            handle_py_exception(what, gilState);
        }
    }
};

namespace
{

// prandtl_fmu: a plain pointer, created once and deleted once, by finalizePythonInterpreter. The stock loader
// kept it in a global std::shared_ptr, whose static destructor (run by exit()'s handlers) freed the PyState
// before the library's destructor function (run later by _dl_fini) assigned nullptr to the destroyed
// shared_ptr: a reference count decremented in freed memory, and a second destruction when it reached zero.
// Where that 128-byte block had been reused meanwhile (Python's, numba's and LLVM's teardown allocate and free
// a lot at exit), the host's heap was corrupted: the "corrupted double-linked list" SIGABRT at interpreter exit
// after FMPy runs (found with valgrind: "Invalid read of size 4 at finalizePythonInterpreter ... inside a
// block of size 128 free'd ... by __run_exit_handlers ... alloc'd by pythonfmu::createInstance"). The
// mutex has a trivial destructor.
std::mutex pyStateMutex{};
PyState* pyState = nullptr;

} // namespace

std::unique_ptr<SlaveInstance> pythonfmu::createInstance(fmu_data data)
{
    {
        auto const lock = std::lock_guard{pyStateMutex};
        if (nullptr == pyState) pyState = new PyState();
    }
    return std::make_unique<PySlaveInstance>(data);
}


extern "C" {

// The PyState instance owns it's own thread for constructing and destroying the Py* from the same thread.
// Creation of an std::thread increments ref counter of a shared library. So, when the client unloads the library
// the library won't be freed, as std::thread is alive, and the std::thread itself waits for de-initialization request.
// Thus, use DllMain on Windows and __attribute__((destructor)) on Linux for signaling to the PyState about de-initialization.
void finalizePythonInterpreter()
{
    auto const lock = std::lock_guard{pyStateMutex};
    delete pyState; // prandtl_fmu: see pyState
    pyState = nullptr;
}
}

namespace
{

#ifdef _WIN32
#    include <windows.h>

BOOL APIENTRY DllMain(HMODULE hModule,
    DWORD ul_reason_for_call,
    LPVOID lpReserved)
{
    switch (ul_reason_for_call) {
        case DLL_PROCESS_ATTACH:
            break;
        case DLL_THREAD_ATTACH:
        case DLL_THREAD_DETACH:
            break;
        case DLL_PROCESS_DETACH:
            finalizePythonInterpreter();
            break;
    }
    return TRUE;
}
#elif defined(__linux__)
__attribute__((destructor)) void onLibraryUnload()
{
    finalizePythonInterpreter();
}
#else
#    error port the code
#endif
} // namespace
