/* SPDX-License-Identifier: LGPL-2.1-or-later */
#include <errno.h>
#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <sys/wait.h>
#include <unistd.h>

#include "ctl/ctl_agent.h"

static pid_t agent_pid;

/* The agent prompts on the controlling terminal (/dev/tty): a terminal on
 * stdin is not enough (`su -c` starts a new session without one, and the
 * agent would only print an error), as systemd's agents check too. */
static bool have_controlling_tty(void) {
        int fd = open("/dev/tty", O_RDONLY | O_NOCTTY | O_CLOEXEC);
        if (fd < 0)
                return false;
        close(fd);
        return true;
}

int ctl_agent_open(void) {
        int fds[2];
        pid_t pid;

        if (agent_pid > 0)
                return 0;
        /* root is never asked; no terminal, nobody to ask; no pkttyagent, no polkit */
        if (geteuid() == 0 || !isatty(STDIN_FILENO) || !have_controlling_tty() || access(CTL_POLKIT_AGENT, X_OK) < 0)
                return 0;
        if (pipe2(fds, O_CLOEXEC) < 0)
                return -errno;
        pid = fork();
        if (pid < 0) {
                int r = -errno;
                close(fds[0]);
                close(fds[1]);
                return r;
        }
        if (pid == 0) {
                char fd_arg[16];
                /* the agent prompts on the terminal, even when our output goes elsewhere */
                if (!isatty(STDOUT_FILENO) || !isatty(STDERR_FILENO)) {
                        int tty = open("/dev/tty", O_WRONLY | O_NOCTTY);
                        if (tty >= 0) {
                                if (!isatty(STDOUT_FILENO))
                                        dup2(tty, STDOUT_FILENO);
                                if (!isatty(STDERR_FILENO))
                                        dup2(tty, STDERR_FILENO);
                                if (tty > STDERR_FILENO)
                                        close(tty);
                        }
                }
                /* the write end goes to the agent: it closes it once registered */
                if (fcntl(fds[1], F_SETFD, 0) < 0)
                        _exit(EXIT_FAILURE);
                snprintf(fd_arg, sizeof(fd_arg), "%d", fds[1]);
                /* for its parent process (us), beside any agent there is */
                execl(CTL_POLKIT_AGENT, CTL_POLKIT_AGENT, "--notify-fd", fd_arg, "--fallback", (char *) NULL);
                _exit(EXIT_FAILURE);
        }
        close(fds[1]);
        agent_pid = pid;
        /* registered (or gone) when the write end closes; not forever */
        struct pollfd p = { .fd = fds[0], .events = POLLIN };
        (void) poll(&p, 1, CTL_AGENT_WAIT_MS);
        close(fds[0]);
        return 1;
}

bool ctl_agent_running(void) {
        return agent_pid > 0;
}

void ctl_agent_close(void) {
        if (agent_pid <= 0)
                return;
        kill(agent_pid, SIGTERM);
        (void) waitpid(agent_pid, NULL, 0);
        agent_pid = 0;
}
