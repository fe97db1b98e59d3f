/* The FMI 2.0 logger callback (fmi2CallbackLogger) is printf-style and variadic, which stable Rust cannot define:
 * this formats the message and hands the text to the sink the Rust side put in the component environment. */
#include <stdarg.h>
#include <stdio.h>

struct silrig_fmi_log_env {
    void (*sink)(void *data, int status, const char *category, const char *message);
    void *data;
};

void silrig_fmi2_logger(void *env, const char *instance, int status, const char *category, const char *message, ...) {
    char text[2048];
    va_list args;
    (void)instance;
    va_start(args, message);
    vsnprintf(text, sizeof text, message ? message : "", args);
    va_end(args);
    struct silrig_fmi_log_env *e = env;
    if (e && e->sink) {
        e->sink(e->data, status, category ? category : "", text);
    }
}
