//! A real single-node Slurm cluster for one test: Debian's `slurmctld` and `slurmd` run in the
//! foreground as children of the test, with `slurm.conf`, state, spool, logs and pid files in a
//! private temporary directory and the two daemons on a free port pair on 127.0.0.1. Dropping
//! the cluster cancels its jobs and stops both daemons, even when the test panics.
//!
//! Authentication is `auth/none` (no munged to start), so the daemons listen on 127.0.0.1 only
//! and run as the user running the test (Slurm's user is that user too): root in CI, anyone
//! else by hand. Two clusters on one machine do not share anything but the binaries.

use std::fs;
use std::net::{TcpListener, TcpStream};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};
use std::thread;
use std::time::{Duration, Instant};

/// The programs the tests run, with the Debian package of each.
const PROGRAMS: &[(&str, &str)] = &[
    ("slurmctld", "slurmctld"),
    ("slurmd", "slurmd"),
    ("sbatch", "slurm-client"),
    ("squeue", "slurm-client"),
    ("scancel", "slurm-client"),
    ("scontrol", "slurm-client"),
    ("sinfo", "slurm-client"),
];

pub struct Cluster {
    dir: tempfile::TempDir,
    conf: PathBuf,
    daemons: Vec<Child>,
    /// From starting the daemons to the node reading `idle`.
    pub started_in: Duration,
}

/// Where `program` is: on PATH, or in an sbin folder (Debian puts the daemons in /usr/sbin,
/// which is not on a normal user's PATH).
fn find(program: &str) -> Option<PathBuf> {
    let path = std::env::var_os("PATH").unwrap_or_default();
    std::env::split_paths(&path)
        .chain(["/usr/sbin", "/usr/local/sbin", "/sbin"].map(PathBuf::from))
        .map(|dir| dir.join(program))
        .find(|p| p.is_file())
}

/// Two ports that were free a moment ago (the daemons bind them right after).
fn free_ports() -> (u16, u16) {
    let a = TcpListener::bind("127.0.0.1:0").unwrap();
    let b = TcpListener::bind("127.0.0.1:0").unwrap();
    (
        a.local_addr().unwrap().port(),
        b.local_addr().unwrap().port(),
    )
}

fn user_name() -> String {
    let out = Command::new("id")
        .arg("-un")
        .output()
        .expect("running id -un");
    String::from_utf8(out.stdout).unwrap().trim().to_string()
}

impl Cluster {
    /// Starts a cluster, or returns `None` when the Slurm packages are missing and
    /// `DUALREP_SKIP_SLURM=1` says to skip (loudly). Without that variable, missing packages
    /// fail the test with the packages to install.
    pub fn start() -> Option<Cluster> {
        let mut missing: Vec<&str> = PROGRAMS
            .iter()
            .filter(|(program, _)| find(program).is_none())
            .map(|(_, package)| *package)
            .collect();
        missing.dedup();
        if !missing.is_empty() {
            if std::env::var("DUALREP_SKIP_SLURM").is_ok_and(|v| v == "1") {
                eprintln!(
                    "\n!!!!!!!! SLURM TESTS SKIPPED (DUALREP_SKIP_SLURM=1): `reproduce --executor \
                     slurm` is NOT tested !!!!!!!!\n"
                );
                return None;
            }
            panic!(
                "the Slurm tests need Debian's slurmctld, slurmd and slurm-client; missing: {}.\n\
                 Install them with `sudo apt-get install -y {}` (`bash tests/run.sh` installs what is \
                 missing, then runs every test), or set DUALREP_SKIP_SLURM=1 to skip these tests.",
                missing.join(", "),
                missing.join(" ")
            );
        }
        // A port taken between choosing it and binding it makes the daemons fail: try again
        // on a fresh pair.
        let mut last_error = String::new();
        for _ in 0..3 {
            match Cluster::try_start() {
                Ok(cluster) => return Some(cluster),
                Err(why) => last_error = why,
            }
        }
        panic!("the test's Slurm cluster did not start: {last_error}");
    }

    fn try_start() -> Result<Cluster, String> {
        let dir = tempfile::Builder::new()
            .prefix("dualrep-slurm-")
            .tempdir()
            .unwrap();
        // Owned: `dir` moves into the cluster below.
        let root = &dir.path().to_path_buf();
        for sub in ["state", "spool", "log"] {
            fs::create_dir(root.join(sub)).unwrap();
        }
        fs::write(root.join("plugstack.conf"), "").unwrap();
        let (ctld_port, slurmd_port) = free_ports();
        let conf = root.join("slurm.conf");
        fs::write(
            &conf,
            slurm_conf(root, ctld_port, slurmd_port, &user_name()),
        )
        .unwrap();

        let start = Instant::now();
        let mut cluster = Cluster {
            daemons: Vec::new(),
            conf,
            dir,
            started_in: Duration::ZERO,
        };
        // slurmd registers with the controller at start and, finding none, tries again a
        // second later; Slurm's commands wait as long before retrying: start the controller
        // first and go on once it listens.
        cluster.spawn("slurmctld", &["-D"])?;
        while TcpStream::connect(("127.0.0.1", ctld_port)).is_err() {
            if start.elapsed() > Duration::from_secs(20) {
                return Err(format!(
                    "slurmctld did not listen on port {ctld_port} within 20 s; logs:\n{}",
                    cluster.logs()
                ));
            }
            thread::sleep(Duration::from_millis(5));
        }
        cluster.spawn("slurmd", &["-D", "-N", "localhost"])?;
        while start.elapsed() < Duration::from_secs(20) {
            let state = cluster.output("sinfo", &["--noheader", "--format=%T"]);
            if String::from_utf8_lossy(&state.stdout).trim() == "idle" {
                cluster.started_in = start.elapsed();
                eprintln!(
                    "slurm: single-node cluster idle {:.2} s after starting its daemons",
                    cluster.started_in.as_secs_f64()
                );
                return Ok(cluster);
            }
            thread::sleep(Duration::from_millis(50));
        }
        Err(format!(
            "the node was not idle after 20 s; logs:\n{}",
            cluster.logs()
        ))
    }

    /// Starts one daemon in the foreground, its output in `log/<program>.out`.
    fn spawn(&mut self, program: &str, args: &[&str]) -> Result<(), String> {
        let log = fs::File::create(self.dir.path().join(format!("log/{program}.out"))).unwrap();
        let child = Command::new(find(program).expect("checked in start"))
            .args(args)
            .env("SLURM_CONF", &self.conf)
            .stdin(Stdio::null())
            .stdout(log.try_clone().unwrap())
            .stderr(log)
            .spawn()
            .map_err(|e| format!("starting {program}: {e}"))?;
        self.daemons.push(child);
        Ok(())
    }

    /// `program args...` against this cluster (its `SLURM_CONF` set), run to completion.
    pub fn output(&self, program: &str, args: &[&str]) -> Output {
        self.command(program)
            .args(args)
            .output()
            .unwrap_or_else(|e| panic!("running {program}: {e}"))
    }

    /// A command that talks to this cluster.
    pub fn command(&self, program: impl AsRef<std::ffi::OsStr>) -> Command {
        let mut command = Command::new(program);
        command.env("SLURM_CONF", &self.conf);
        command
    }

    /// The daemons' logs, for a failure message.
    pub fn logs(&self) -> String {
        let mut text = String::new();
        for name in ["slurmctld.log", "slurmd.log", "slurmctld.out", "slurmd.out"] {
            let path = self.dir.path().join("log").join(name);
            let body = fs::read_to_string(&path).unwrap_or_default();
            let tail: Vec<&str> = body.lines().rev().take(20).collect();
            text += &format!("--- {name} (last lines)\n");
            for line in tail.into_iter().rev() {
                text += line;
                text.push('\n');
            }
        }
        text
    }
}

impl Drop for Cluster {
    fn drop(&mut self) {
        // Jobs first: their slurmstepd processes outlive slurmd by design.
        let _ = self.command("scancel").arg("--me").output();
        let deadline = Instant::now() + Duration::from_secs(10);
        while Instant::now() < deadline {
            let out = self.command("squeue").args(["--me", "--noheader"]).output();
            if out.is_ok_and(|o| o.stdout.iter().all(u8::is_ascii_whitespace)) {
                break;
            }
            thread::sleep(Duration::from_millis(100));
        }
        let stop = Instant::now();
        for daemon in &self.daemons {
            let _ = Command::new("kill")
                .args(["-TERM", &daemon.id().to_string()])
                .status();
        }
        for daemon in &mut self.daemons {
            let deadline = Instant::now() + Duration::from_secs(10);
            while daemon.try_wait().ok().flatten().is_none() && Instant::now() < deadline {
                thread::sleep(Duration::from_millis(20));
            }
            if daemon.try_wait().ok().flatten().is_none() {
                let _ = daemon.kill();
                let _ = daemon.wait();
            }
        }
        eprintln!(
            "slurm: daemons exited {:.2} s after SIGTERM",
            stop.elapsed().as_secs_f64()
        );
    }
}

/// A one-node cluster on 127.0.0.1 whose every file is under `root`.
fn slurm_conf(root: &Path, ctld_port: u16, slurmd_port: u16, user: &str) -> String {
    let r = root.display();
    format!(
        "# The dualrep tests' private cluster (tests/support/slurm_cluster.rs).
ClusterName=dualreptest
SlurmctldHost=localhost(127.0.0.1)
SlurmctldPort={ctld_port}
SlurmdPort={slurmd_port}
# Only this machine can reach the daemons; auth/none needs no munged.
CommunicationParameters=NoInAddrAny,NoCtldInAddrAny
AuthType=auth/none
CredType=cred/none
SlurmUser={user}
SlurmdUser={user}
StateSaveLocation={r}/state
SlurmdSpoolDir={r}/spool
SlurmctldPidFile={r}/slurmctld.pid
SlurmdPidFile={r}/slurmd.pid
SlurmctldLogFile={r}/log/slurmctld.log
SlurmdLogFile={r}/log/slurmd.log
PlugStackConfig={r}/plugstack.conf
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
# The node has 2 CPUs whatever the machine has.
SlurmdParameters=config_overrides
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
MpiDefault=none
MailProg=/bin/true
ReturnToService=2
NodeName=localhost NodeAddr=127.0.0.1 CPUs=2 State=UNKNOWN
PartitionName=test Nodes=localhost Default=YES MaxTime=INFINITE State=UP
"
    )
}
